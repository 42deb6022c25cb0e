"""Campaigns on a ``dask.distributed.Client``: many independent fits or presses.

- ``fit_each(bundles, out_root, client, **options)``: one ``wagashi.fit`` per
  bundle, each a task, into ``out_root/NNNN-NAME``.
- ``press_sweep(bundle, out_root, client, grid, **options)``: one
  ``wagashi.press`` per point of a parameter grid over the bundle's
  ``experiment.toml`` keys, into ``out_root/NNNN/press`` (the edited bundle in
  ``out_root/NNNN/bundle``).

Results come back in input order. A task that fails gives a ``TaskFailure``
(its input, output folder and message) in its place, and the other tasks
finish. Each task writes only its own folder, atomically (the commands build a
hidden temporary folder and move it into place when complete); tasks share
nothing but their inputs.

Threads: each task runs in a rayon pool of its own, of ``threads`` threads
(default 1). A Dask worker runs as many tasks at once as it has threads
(``nthreads``), so with the default the campaign uses as many cores as the
workers have threads in all: N workers of one thread on N cores run N tasks on
N cores, not N pools of N threads each. A worker that owns more cores than it
runs tasks (a Slurm job of 8 cores running ``nthreads=2``) gives each task
``threads=4``.

Any ``Client`` works: a ``LocalCluster`` on a laptop, or a Slurm or PBS cluster
through dask-jobqueue (see python/README.md).
"""

from __future__ import annotations

import itertools
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence, Union

import wagashi

__all__ = ["TaskFailure", "failures", "fit_each", "press_sweep", "grid_points"]


@dataclass
class TaskFailure:
    """A task that failed: what it was given, where it would have written, and why.

    Attributes:
        input: the task's input (the bundle of ``fit_each``; for
            ``press_sweep`` the grid point, a dict of dotted keys to values).
        output: the folder the task would have written.
        message: the one-line error (``file:line: key: cause``), or the
            exception's text for an error outside wagashi (a lost worker).
        error_type: the exception's class name (``WagashiError``, ...).
    """

    input: Any
    output: str
    message: str
    error_type: str

    def __bool__(self) -> bool:
        return False


def failures(results: Iterable[Any]) -> list:
    """The ``TaskFailure`` entries of a result list, in order."""
    return [r for r in results if isinstance(r, TaskFailure)]


def _task_threads(threads: int | None) -> int:
    """The rayon pool size of one task: ``threads``, else 1 (see the module docs)."""
    return 1 if threads is None else threads


def _fit_task(bundle: str, out: str, threads: int | None, options: dict):
    try:
        return dict(wagashi.fit(bundle, out, threads=_task_threads(threads), **options))
    except Exception as e:  # noqa: BLE001 -- every failure is reported, the campaign goes on
        return TaskFailure(bundle, out, str(e), type(e).__name__)


def _press_task(bundle: str, point: dict, folder: str, threads: int | None, options: dict):
    folder_path = Path(folder)
    try:
        edited = folder_path / "bundle"
        if edited.exists():
            # A previous run of the same task: its copy is rebuilt from the input.
            import shutil

            shutil.rmtree(edited)
        folder_path.mkdir(parents=True, exist_ok=True)
        wagashi.set_bundle_keys(bundle, edited, point)
        result = wagashi.press(edited, folder_path / "press", threads=_task_threads(threads), **options)
        summary = dict(result)
        summary["force_t_s"] = result.force["t_s"].tolist()
        summary["force_N"] = result.force["force_N"].tolist()
        return summary
    except Exception as e:  # noqa: BLE001 -- every failure is reported, the campaign goes on
        return TaskFailure(point, str(folder_path / "press"), str(e), type(e).__name__)


# Options naming files: made absolute before they go to the workers, whose
# working folder may differ from the client's.
_PATH_OPTIONS = ("materials",)


def _absolute_paths(options: dict) -> dict:
    return {k: (os.fspath(Path(v).absolute()) if k in _PATH_OPTIONS and v is not None else v) for k, v in options.items()}


def _safe_name(path: str) -> str:
    name = Path(path.rstrip("/\\")).name or "bundle"
    return re.sub(r"[^A-Za-z0-9._+-]", "_", name)


def _gather(client, futures, inputs, outputs) -> list:
    results = []
    for future, given, out in zip(futures, inputs, outputs):
        try:
            results.append(future.result())
        except Exception as e:  # noqa: BLE001 -- a lost worker or a cancelled task
            results.append(TaskFailure(given, out, str(e), type(e).__name__))
    return results


def fit_each(
    bundles: Sequence[Union[str, "os.PathLike[str]"]],
    out_root: Union[str, "os.PathLike[str]"],
    client,
    *,
    threads: int | None = None,
    **options: Any,
) -> list:
    """One ``wagashi.fit`` per bundle on ``client``, each a task writing
    ``out_root/NNNN-NAME`` (NNNN: the bundle's 0-based index, NAME: its folder
    name). Relative paths (the bundles, ``out_root``, ``materials``) are taken
from the client's working folder. Returns, in the order of ``bundles``, each fit's ``fit.json`` as a
    dict, or a ``TaskFailure``. ``options`` are ``wagashi.fit``'s; ``threads``
    the rayon pool per task (default: see the module docs).
    """
    root = Path(out_root)
    root.mkdir(parents=True, exist_ok=True)
    paths = [os.fspath(Path(b).absolute()) for b in bundles]
    outs = [os.fspath((root / f"{i:04d}-{_safe_name(p)}").absolute()) for i, p in enumerate(paths)]
    futures = [
        client.submit(_fit_task, p, o, threads, _absolute_paths(options), key=f"wagashi-fit-{i:04d}-{_token(o)}", pure=False)
        for i, (p, o) in enumerate(zip(paths, outs))
    ]
    return _gather(client, futures, [os.fspath(b) for b in bundles], outs)


def grid_points(grid: Union[Mapping[str, Sequence[Any]], Sequence[Mapping[str, Any]]]) -> list:
    """The points of a parameter grid, in order: a mapping of dotted keys to
    value lists gives their Cartesian product (the last key varying fastest); a
    sequence of mappings is taken as the points themselves."""
    if isinstance(grid, Mapping):
        keys = list(grid)
        for k in keys:
            if isinstance(grid[k], (str, bytes)) or not isinstance(grid[k], Sequence):
                raise wagashi.OptionError(f"grid: {k}: give a list of values")
        return [dict(zip(keys, values)) for values in itertools.product(*(grid[k] for k in keys))]
    return [dict(point) for point in grid]


def press_sweep(
    bundle: Union[str, "os.PathLike[str]"],
    out_root: Union[str, "os.PathLike[str]"],
    client,
    grid: Union[Mapping[str, Sequence[Any]], Sequence[Mapping[str, Any]]],
    *,
    threads: int | None = None,
    **options: Any,
) -> list:
    """One ``wagashi.press`` per point of ``grid`` (see ``grid_points``) over
    dotted ``experiment.toml`` keys, e.g. ``{"materials.mat1.E1_MPa": [0.01,
    0.02]}`` or ``[{"protocol.waypoints": [[0, 0], [10, 2]], "protocol.release_s":
    10.0}, ...]``; ``None`` removes a key (``"data": None`` drops the measured
    data). Point i writes ``out_root/NNNN/bundle`` (the edited copy of the
    bundle; the input is never modified) and ``out_root/NNNN/press`` (the press
    output). Returns, in grid order, each press's ``summary.json`` as a dict
    with the force curve added as the lists ``force_t_s`` [s] and ``force_N``
    [N], or a ``TaskFailure``. ``options`` are ``wagashi.press``'s.
    """
    root = Path(out_root)
    root.mkdir(parents=True, exist_ok=True)
    source = os.fspath(Path(bundle).absolute())
    points = grid_points(grid)
    folders = [os.fspath((root / f"{i:04d}").absolute()) for i in range(len(points))]
    futures = [
        client.submit(_press_task, source, p, f, threads, _absolute_paths(options), key=f"wagashi-press-{i:04d}-{_token(f)}", pure=False)
        for i, (p, f) in enumerate(zip(points, folders))
    ]
    return _gather(client, futures, points, [os.fspath(Path(f) / "press") for f in folders])


def _token(text: str) -> str:
    import hashlib

    return hashlib.sha1(text.encode()).hexdigest()[:10]
