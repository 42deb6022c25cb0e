"""Shared fixtures: the repository, the `wagashi` binary the Python results are
compared with, the shared data folder, and comparisons of output folders.

Tests that need ``../shared/data`` skip with a message when it is absent, and
fail instead when ``CI`` is set (to anything but empty, ``false`` or ``0``), as
the Rust tests do.
"""

from __future__ import annotations

import csv
import io
import json
import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]

# Keys holding wall-clock times [s], which differ from run to run.
TIMING_KEYS = {"wall_time_s", "total_time_s", "wall_s", "time_s", "mesh_time_s", "report_time_s"}
# Columns of steps.csv holding wall-clock times [s].
TIMING_COLUMNS = {"solve_s"}


def on_ci() -> bool:
    return os.environ.get("CI", "") not in ("", "false", "0")


def need(what: str, path: Path) -> Path:
    """``path``, or a skip naming ``what`` (a failure on CI) when it is missing."""
    if path.exists():
        return path
    message = f"needs {what}, which is missing at {path}"
    if on_ci():
        pytest.fail(f"{message}; on CI it must be there")
    pytest.skip(message)


@pytest.fixture(scope="session")
def wagashi_bin() -> Path:
    """The `wagashi` binary: $WAGASHI_BIN, else $CARGO_TARGET_DIR/release/wagashi, else target/release/wagashi."""
    if os.environ.get("WAGASHI_BIN"):
        path = Path(os.environ["WAGASHI_BIN"])
    else:
        target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
        path = target / "release" / "wagashi"
    return need("the wagashi binary (cargo build --release -p wagashi)", path)


@pytest.fixture(scope="session")
def fungi() -> Path:
    """The shared fungi-steak double-compression records."""
    return need("../shared/data (the fungi-steak records)", REPO.parent / "shared" / "data" / "real" / "fungi-steak")


def cli(binary: Path, args, cwd: Path, check: bool = True) -> subprocess.CompletedProcess:
    """Runs ``wagashi ARGS`` in ``cwd``; with ``check``, a failure fails the test with its stderr."""
    done = subprocess.run([str(binary), *map(str, args)], cwd=cwd, capture_output=True, text=True)
    if check and done.returncode != 0:
        pytest.fail(f"wagashi {' '.join(map(str, args))}: status {done.returncode}: {done.stderr}")
    return done


@pytest.fixture
def sides(tmp_path, monkeypatch):
    """Two working folders, ``(c, p)``: the binary runs in ``c``, Python in
    ``p`` (the current folder during the test), so that both write outputs of
    the same relative names and the paths the outputs record agree."""
    c, p = tmp_path / "c", tmp_path / "p"
    c.mkdir()
    p.mkdir()
    monkeypatch.chdir(p)
    return c, p


def without_timings(value):
    """A JSON value with the wall-clock keys removed, recursively."""
    if isinstance(value, dict):
        return {k: without_timings(v) for k, v in value.items() if k not in TIMING_KEYS}
    if isinstance(value, list):
        return [without_timings(v) for v in value]
    return value


def _csv_without_timings(text: str) -> list:
    rows = list(csv.reader(io.StringIO(text)))
    keep = [i for i, name in enumerate(rows[0]) if name not in TIMING_COLUMNS]
    return [[row[i] for i in keep] for row in rows]


def assert_same_outputs(a: Path, b: Path) -> int:
    """The folders ``a`` and ``b`` hold the same files with the same bytes,
    except the wall-clock times (JSON keys in ``TIMING_KEYS``, the ``solve_s``
    column of steps.csv), whose other values must be equal exactly. Returns the
    number of files compared."""
    files_a = sorted(p.relative_to(a) for p in a.rglob("*") if p.is_file())
    files_b = sorted(p.relative_to(b) for p in b.rglob("*") if p.is_file())
    assert files_a == files_b
    for rel in files_a:
        x, y = (a / rel).read_bytes(), (b / rel).read_bytes()
        if x == y:
            continue
        if rel.suffix == ".json" and rel.name != "wagashi-manifest.json":
            assert without_timings(json.loads(x)) == without_timings(json.loads(y)), rel
        elif rel.name == "steps.csv":
            assert _csv_without_timings(x.decode()) == _csv_without_timings(y.decode()), rel
        else:
            raise AssertionError(f"{rel}: differs between {a} and {b}")
    return len(files_a)


def five_element_start(path: Path, material: str = "mat1") -> Path:
    """A materials file giving ``material`` only its model: every parameter is fitted."""
    path.write_text(f'[materials.{material}]\nmodel = "five-element"\n', encoding="utf-8")
    return path
