"""wagashi: the finite-element engine for soft foods, from Python.

Each function runs the `wagashi` command of the same name through the same Rust
code as the binary, so its outputs are the command line's, bit for bit, and
returns what the command writes as Python objects:

- ``press(bundle, out, **options) -> PressResult``: ``summary.json`` as a dict,
  with the force curve and the markers as numpy arrays (``.force``, ``.markers``).
- ``fit(bundles, out, **options) -> Result``: ``fit.json``.
- ``diagnose(calibrate, validate, out, **options) -> Result``: ``diagnosis.json``.
- ``mesh(surface, out, **options) -> Result``: the quality report (``--report``).
- ``tpa(inputs, **options) -> list[dict]``: ``wagashi tpa --json``.
- ``import_records(kind, files, out, **options) -> list[Path]``: ``wagashi import``.
- ``set_bundle_keys(bundle, target, keys) -> Path``: a copy of a bundle with
  dotted ``experiment.toml`` keys set.

Options take the command line's names with underscores: ``size_mm=6.0`` is
``--size-mm 6.0``, ``axisymmetric=True`` is ``--axisymmetric`` (``False`` or
``None`` leaves an option out), a list repeats the option once per item. The
option ``threads=N`` is Python's own: the run uses a rayon pool of N threads
(default: one per core), which is how ``wagashi.distributed`` keeps N workers on
N cores from oversubscribing.

The GIL is released while a command runs. A failure raises ``WagashiError``
whose message is the command line's one line (``file:line: key: cause``);
options that do not parse raise its subclass ``OptionError``.
"""

from __future__ import annotations

import csv
import json
import os
import tempfile
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence, Union

import numpy as np

from ._wagashi import OptionError, WagashiError, __version__
from ._wagashi import run as _run
from ._wagashi import set_toml_keys as _set_toml_keys

__all__ = [
    "OptionError",
    "PressResult",
    "Result",
    "WagashiError",
    "command_line",
    "diagnose",
    "fit",
    "import_records",
    "mesh",
    "press",
    "run",
    "set_bundle_keys",
    "tpa",
    "__version__",
]

PathLike = Union[str, "os.PathLike[str]"]


class Result(dict):
    """A command's JSON output as a dict, with what it printed and where it wrote.

    Attributes:
        output: the output folder (or file) the command wrote.
        report: what the command prints for the user (its stdout on the command line).
    """

    def __init__(self, data: Mapping[str, Any], output: Path, report: str):
        super().__init__(data)
        self.output = output
        self.report = report


class PressResult(Result):
    """``press``'s ``summary.json`` as a dict, plus the curves it wrote.

    Attributes:
        force: ``force.csv`` as a structured numpy array with the float fields
            ``t_s`` [s] and ``force_N`` [N] (the simulated bottom force).
        markers: ``markers.csv`` as a structured numpy array with the fields
            ``marker`` (str), ``t_s`` [s], ``x_mm``, ``y_mm`` (and ``z_mm`` in
            3D) [mm]; ``None`` when the bundle has no markers.
    """

    def __init__(self, data, output, report, force, markers):
        super().__init__(data, output, report)
        self.force = force
        self.markers = markers


def command_line(command: Sequence[str], positional: Iterable[PathLike], options: Mapping[str, Any]) -> list[str]:
    """The argument list (without the program name) of ``wagashi COMMAND``.

    ``options`` use the command line's long names with underscores for dashes;
    ``True`` gives the bare flag, ``False`` and ``None`` leave it out, a list or
    tuple repeats the option per item, anything else is its ``str`` (floats by
    ``repr``, which round-trips exactly). Values are attached with ``=`` and the
    positional arguments follow ``--``, so neither can be taken for an option.
    """
    argv = list(command)
    for name, value in options.items():
        if not name.isidentifier():
            raise OptionError(f"{name!r}: not an option name")
        flag = "--" + name.replace("_", "-")
        if value is None or value is False:
            continue
        if value is True:
            argv.append(flag)
        elif isinstance(value, (list, tuple)):
            argv.extend(f"{flag}={_text(v)}" for v in value)
        else:
            argv.append(f"{flag}={_text(value)}")
    argv.append("--")
    argv.extend(os.fspath(p) for p in positional)
    return argv


def _text(value: Any) -> str:
    if isinstance(value, bool):
        raise OptionError(f"{value!r}: a flag takes True or False alone, not inside a list")
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    return str(value)


def run(argv: Sequence[str], threads: int | None = None) -> str:
    """Runs ``wagashi ARGV...`` (without the program name) and returns what it prints."""
    return _run([str(a) for a in argv], threads)


def _read_json(path: Path) -> Any:
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def _force_array(path: Path) -> np.ndarray:
    with open(path, encoding="utf-8", newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    dtype = [(name, "f8") for name in header]
    return np.array([tuple(float(x) for x in row) for row in body], dtype=dtype)


def _markers_array(path: Path) -> np.ndarray:
    with open(path, encoding="utf-8", newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    width = max([len(r[0]) for r in body] + [1])
    dtype = [(header[0], f"U{width}")] + [(name, "f8") for name in header[1:]]
    return np.array([(row[0], *(float(x) for x in row[1:])) for row in body], dtype=dtype)


def press(bundle: PathLike, out: PathLike, *, threads: int | None = None, **options: Any) -> PressResult:
    """``wagashi press BUNDLE -o OUT``: simulates a bundle into the folder ``out``.

    Returns ``summary.json`` as a dict with ``.force`` and ``.markers`` (see
    ``PressResult``). Options as the command line's: ``size_mm``, ``integrator``,
    ``rtol``, ``dt``, ``materials``, ``output_dt``, ``pvd``, ``force``,
    ``allow_large``, ``gltf``, ``mesh_mode``, ``axisymmetric``, ``fbar``.
    """
    out = Path(out)
    report = run(command_line(["press", f"--output={os.fspath(out)}"], [bundle], options), threads)
    summary = _read_json(out / "summary.json")
    markers = _markers_array(out / "markers.csv") if (out / "markers.csv").exists() else None
    return PressResult(summary, out, report, _force_array(out / "force.csv"), markers)


def fit(bundles: Union[PathLike, Sequence[PathLike]], out: PathLike, *, threads: int | None = None, **options: Any) -> Result:
    """``wagashi fit BUNDLE... -o OUT``: returns ``fit.json`` as a dict.

    Options: ``procedure``, ``materials``, ``starts``, ``size_mm``,
    ``axisymmetric``, ``marker_sigma_mm``, ``force``, ``allow_large``, ``fbar``.
    """
    out = Path(out)
    report = run(command_line(["fit", f"--output={os.fspath(out)}"], _paths(bundles), options), threads)
    return Result(_read_json(out / "fit.json"), out, report)


def diagnose(
    calibrate: Union[PathLike, Sequence[PathLike]],
    validate: Union[PathLike, Sequence[PathLike], None],
    out: PathLike,
    *,
    threads: int | None = None,
    **options: Any,
) -> Result:
    """``wagashi diagnose --calibrate BUNDLE... --validate BUNDLE... -o OUT``:
    returns ``diagnosis.json`` as a dict.

    Options: ``materials``, ``effects``, ``starts``, ``seed``, ``size_mm``,
    ``axisymmetric``, ``marker_sigma_mm``, ``force``, ``allow_large``.
    """
    out = Path(out)
    for name in ("calibrate", "validate", "output"):
        if name in options:
            raise OptionError(f"{name}: given by the positional arguments")
    opts = dict(options)
    opts["calibrate"] = [os.fspath(p) for p in _paths(calibrate)]
    opts["validate"] = [os.fspath(p) for p in _paths(validate)] if validate is not None else None
    report = run(command_line(["diagnose", f"--output={os.fspath(out)}"], [], opts), threads)
    return Result(_read_json(out / "diagnosis.json"), out, report)


def mesh(surface: PathLike, out: PathLike, *, threads: int | None = None, **options: Any) -> Result:
    """``wagashi mesh SURFACE -o OUT --size-mm H``: meshes a surface into the
    mesh file ``out`` (.msh, .vtu or TetGen .node) and returns the quality
    report as a dict (the file of ``report=PATH`` when given, else a report
    written to a temporary folder and removed).

    Options: ``size_mm`` (required), ``mode``, ``layers_mm``, ``grade_levels``,
    ``report``, ``units``, ``scale``, ``force``.
    """
    out = Path(out)
    opts = dict(options)
    with tempfile.TemporaryDirectory(prefix="wagashi-mesh-") as tmp:
        if opts.get("report") is None:
            opts["report"] = Path(tmp) / "report.json"
        text = run(command_line(["mesh", f"--output={os.fspath(out)}"], [surface], opts), threads)
        return Result(_read_json(Path(opts["report"])), out, text)


def tpa(inputs: Union[PathLike, Sequence[PathLike]], *, threads: int | None = None, **options: Any) -> list:
    """``wagashi tpa INPUT... --json``: the texture profile of each input (raw
    exports, bundles or press outputs), one dict per input, in order.

    Options: ``output`` (also write tpa.csv, tpa.svg and summary.json there),
    ``force``, ``threshold_N``, ``smooth_samples``.
    """
    opts = dict(options)
    opts["json"] = True
    text = run(command_line(["tpa"], _paths(inputs), opts), threads)
    # With --output the JSON array is followed by nothing else (`--json` drops the table).
    return json.loads(text)


def import_records(kind: str, files: Union[PathLike, Sequence[PathLike]], out: PathLike, **options: Any) -> list:
    """``wagashi import KIND FILE... -o OUT``: raw texture-analyser exports
    (``kind``: ``"rheometer"`` or ``"exponent"``) into bundles, one folder per
    file under ``out``; returns the bundle folders, in the order of ``files``.

    Options: ``cylinder_radius_mm`` (required), ``height_mm``,
    ``start_height_mm``, ``material``, ``model``, ``contact``, ``stroke``,
    ``every``, ``force``.
    """
    out = Path(out)
    paths = _paths(files)
    run(command_line(["import", kind, f"--output={os.fspath(out)}"], paths, options))
    return [out / Path(os.fspath(p)).stem for p in paths]


def set_bundle_keys(bundle: PathLike, target: PathLike, keys: Mapping[str, Any]) -> Path:
    """Copies the bundle folder ``bundle`` to ``target`` (which must not exist)
    with dotted keys of its ``experiment.toml`` set, e.g.
    ``{"protocol.end_s": 300.0, "materials.mat1.E1_MPa": 0.02}``; ``None``
    removes a key (``{"data": None}`` drops the measured data). The input is
    never modified. The copy is built beside ``target`` and renamed into
    place, so ``target`` is either complete or absent. Returns ``target``.
    """
    import shutil
    import uuid

    src, target = Path(bundle), Path(target)
    experiment = src / "experiment.toml"
    try:
        text = experiment.read_text(encoding="utf-8")
    except OSError as e:
        raise WagashiError(f"{experiment}: cannot read: {e.strerror or e}") from None
    pairs = [(str(k), json.dumps(v, allow_nan=False)) for k, v in keys.items()]
    edited = _set_toml_keys(os.fspath(experiment), text, pairs)
    if target.exists():
        raise WagashiError(f"{target}: exists; set_bundle_keys writes a new folder")
    # Built beside the target and renamed into place: never a partial copy.
    partial = target.parent / f".{target.name}.partial-{uuid.uuid4().hex[:12]}"
    try:
        shutil.copytree(src, partial)
        (partial / "experiment.toml").write_text(edited, encoding="utf-8")
        os.rename(partial, target)
    finally:
        shutil.rmtree(partial, ignore_errors=True)
    return target


def _paths(value: Union[PathLike, Sequence[PathLike], None]) -> list:
    if value is None:
        return []
    if isinstance(value, (str, os.PathLike)):
        return [value]
    return list(value)
