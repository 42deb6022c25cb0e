"""The Python API against the `wagashi` binary: the same outputs, bit for bit
(wall-clock times aside), and the same one-line errors, as exceptions."""

from __future__ import annotations

import json
import os
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import wagashi
from conftest import REPO, assert_same_outputs, cli, five_element_start, without_timings

MAT1_2D = REPO / "examples" / "paper" / "mat1-2d"
DOUBLE = REPO / "examples" / "paper" / "double-compression"


def test_press_matches_the_cli_bit_for_bit(sides, wagashi_bin):
    c, p = sides
    cli(wagashi_bin, ["press", MAT1_2D, "-o", "out", "--size-mm", "10"], c)
    result = wagashi.press(MAT1_2D, "out", size_mm=10.0)
    assert assert_same_outputs(c / "out", p / "out") >= 7
    # The dict is summary.json; the arrays are force.csv exactly.
    summary = json.loads((p / "out" / "summary.json").read_text())
    assert dict(result) == summary
    rows = np.loadtxt(c / "out" / "force.csv", delimiter=",", skiprows=1)
    assert result.force.dtype.names == ("t_s", "force_N")
    assert np.array_equal(result.force["t_s"], rows[:, 0]) and np.array_equal(result.force["force_N"], rows[:, 1])
    assert result.markers is None
    assert result.output == Path("out") and "peak force" in result.report


def test_press_markers_are_the_simulated_markers_csv(sides, wagashi_bin):
    # mat1-2d with two measured markers on its top corners (2D: no z column).
    c, p = sides
    for side in (c, p):
        bundle = wagashi.set_bundle_keys(MAT1_2D, side / "marked", {"data.markers": "markers.csv"})
        (bundle / "markers.csv").write_text(
            "marker,t_s,x_mm,y_mm\nm01,0.0,0.0,59.5\nm01,210.93,0.1,53.7\nm02,0.0,58.0,59.5\nm02,400.0,58.1,59.0\n"
        )
    cli(wagashi_bin, ["press", "marked", "-o", "out", "--size-mm", "10"], c)
    result = wagashi.press("marked", "out", size_mm=10.0)
    assert_same_outputs(c / "out", p / "out")
    rows = (p / "out" / "markers.csv").read_text().splitlines()
    assert result.markers.dtype.names == ("marker", "t_s", "x_mm", "y_mm") and len(result.markers) == len(rows) - 1
    for row, got in zip(rows[1:], result.markers):
        name, *numbers = row.split(",")
        assert got["marker"] == name and [got[k] for k in ("t_s", "x_mm", "y_mm")] == [float(x) for x in numbers]
    assert result["markers"] == 2


def test_press_of_a_double_compression_and_tpa_match_the_cli(sides, wagashi_bin):
    # The double compression as its axisymmetric section: tpa.json in the output.
    c, p = sides
    cli(wagashi_bin, ["press", DOUBLE, "-o", "out", "--size-mm", "4", "--axisymmetric"], c)
    wagashi.press(DOUBLE, "out", size_mm=4.0, axisymmetric=True)
    assert_same_outputs(c / "out", p / "out")
    assert (p / "out" / "tpa.json").is_file()
    expected = json.loads(cli(wagashi_bin, ["tpa", "out", "out", "--json"], c).stdout)
    assert wagashi.tpa(["out", "out"]) == expected
    assert len(expected) == 2 and expected[0]["hardness_N"] > 0


def test_fit_matches_the_cli_bit_for_bit(sides, wagashi_bin):
    c, p = sides
    for side in (c, p):
        cli(wagashi_bin, ["press", MAT1_2D, "-o", "measured", "--size-mm", "10"], side)
        five_element_start(side / "start.toml")
    cli(wagashi_bin, ["fit", "measured", "-o", "out", "--materials", "start.toml", "--size-mm", "20", "--starts", "1"], c)
    result = wagashi.fit("measured", "out", materials="start.toml", size_mm=20.0, starts=1)
    assert_same_outputs(c / "out", p / "out")
    assert without_timings(dict(result)) == without_timings(json.loads((c / "out" / "fit.json").read_text()))
    assert set(result["sets"]) == {"force", "shape"} and "mat1.c3_MPa_s" in result.report


def test_diagnose_matches_the_cli_bit_for_bit(sides, wagashi_bin):
    c, p = sides
    for side in (c, p):
        cli(wagashi_bin, ["press", MAT1_2D, "-o", "a", "--size-mm", "10"], side)
        cli(wagashi_bin, ["press", MAT1_2D, "-o", "b", "--size-mm", "5"], side)
        five_element_start(side / "start.toml")
    args = ["--materials", "start.toml", "--size-mm", "20", "--starts", "1", "--effects", "force-offset"]
    cli(wagashi_bin, ["diagnose", "--calibrate", "a", "--validate", "b", "-o", "out", *args], c)
    result = wagashi.diagnose("a", "b", "out", materials="start.toml", size_mm=20.0, starts=1, effects="force-offset")
    assert_same_outputs(c / "out", p / "out")
    assert "force-offset" in result["candidates"] and result["verdict"]


def test_mesh_matches_the_cli_bit_for_bit(sides, wagashi_bin):
    c, p = sides
    bunny = REPO / "tests" / "fixtures" / "npm_bunny.obj"
    args = ["--size-mm", "2", "--mode", "envelope"]
    cli(wagashi_bin, ["mesh", bunny, "-o", "bunny.msh", "--report", "report.json", *args], c)
    result = wagashi.mesh(bunny, "bunny.msh", size_mm=2.0, mode="envelope")
    assert (c / "bunny.msh").read_bytes() == (p / "bunny.msh").read_bytes()
    expected = json.loads((c / "report.json").read_text())
    assert without_timings(dict(result)) == without_timings(expected)
    assert result["quality"]["num_cells"] > 0
    # Without report=, the report is read from a temporary folder and removed.
    assert sorted(x.name for x in p.iterdir()) == ["bunny.msh"]


def _bad_bundle(tmp_path: Path) -> Path:
    """mat1-2d with a word for a number."""
    return wagashi.set_bundle_keys(MAT1_2D, tmp_path / "bad", {"materials.mat1.E1_MPa": "stiff"})


def test_errors_are_exceptions_with_the_cli_line(tmp_path, monkeypatch, wagashi_bin):
    monkeypatch.chdir(tmp_path)  # the binary runs in the same folder: the same relative paths
    bad = _bad_bundle(tmp_path)
    done = cli(wagashi_bin, ["press", bad, "-o", "out"], tmp_path, check=False)
    assert done.returncode == 1
    line = done.stderr.strip()
    assert line.startswith("error: ") and "\n" not in line
    with pytest.raises(wagashi.WagashiError) as caught:
        wagashi.press(bad, "out")
    assert str(caught.value) == line.removeprefix("error: ")
    assert "experiment.toml:" in str(caught.value) and "E1_MPa" in str(caught.value)
    assert not (tmp_path / "out").exists()

    # Options that do not parse: OptionError, a WagashiError, with clap's first line.
    done = cli(wagashi_bin, ["press", MAT1_2D, "-o", "out", "--size-mm", "-2.0"], tmp_path, check=False)
    assert done.returncode == 2
    with pytest.raises(wagashi.OptionError) as caught:
        wagashi.press(MAT1_2D, "out", size_mm=-2.0)
    assert isinstance(caught.value, wagashi.WagashiError)
    assert str(caught.value) == done.stderr.splitlines()[0].removeprefix("error: ")
    with pytest.raises(wagashi.OptionError, match="--no-such-option"):
        wagashi.fit(MAT1_2D, "out", no_such_option=1)
    # An existing output is refused as on the command line, and kept.
    wagashi.press(MAT1_2D, "first", size_mm=20.0)
    with pytest.raises(wagashi.WagashiError, match="pass --force"):
        wagashi.press(MAT1_2D, "first", size_mm=20.0)
    wagashi.press(MAT1_2D, "first", size_mm=20.0, force=True)


def test_the_gil_is_released_and_threads_do_not_change_results(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    results = {}

    def work():
        results["pooled"] = wagashi.press(MAT1_2D, "pooled", size_mm=1.0, threads=1)

    worker = threading.Thread(target=work)
    ticks = 0
    start = time.perf_counter()
    worker.start()
    while worker.is_alive():
        ticks += 1
        time.sleep(0.001)
    elapsed = time.perf_counter() - start
    # With the GIL held for the whole run the loop would not turn during it;
    # released, it turns about once a millisecond.
    assert elapsed > 0.05 and ticks >= 10, (ticks, elapsed)
    default = wagashi.press(MAT1_2D, "default", size_mm=1.0)
    assert (tmp_path / "pooled" / "force.csv").read_bytes() == (tmp_path / "default" / "force.csv").read_bytes()
    assert results["pooled"]["peak_force_N"] == default["peak_force_N"]
    with pytest.raises(wagashi.OptionError, match="threads"):
        wagashi.press(MAT1_2D, "zero", threads=0)


def test_set_bundle_keys_edits_a_copy(tmp_path):
    before = (MAT1_2D / "experiment.toml").read_bytes()
    copy = wagashi.set_bundle_keys(
        MAT1_2D, tmp_path / "copy", {"materials.mat1.E1_MPa": 0.05, "protocol.end_s": 300.0, "specimen.mass_g": None}
    )
    assert (MAT1_2D / "experiment.toml").read_bytes() == before
    import tomllib

    doc = tomllib.loads((copy / "experiment.toml").read_text())
    assert doc["materials"]["mat1"]["E1_MPa"] == 0.05 and doc["protocol"]["end_s"] == 300.0
    assert "mass_g" not in doc["specimen"]
    with pytest.raises(wagashi.OptionError, match="not a table"):
        wagashi.set_bundle_keys(MAT1_2D, tmp_path / "x", {"protocol.end_s.deeper": 1})
    with pytest.raises(wagashi.WagashiError, match="exists"):
        wagashi.set_bundle_keys(MAT1_2D, copy, {})
    with pytest.raises(wagashi.WagashiError, match="experiment.toml: cannot read"):
        wagashi.set_bundle_keys(tmp_path / "none", tmp_path / "y", {})
    # Nothing left behind: neither the refused targets nor a partial copy.
    assert sorted(p.name for p in tmp_path.iterdir()) == ["copy"]


def test_fungi_records_import_and_fit_as_the_cli(sides, wagashi_bin, fungi):
    c, p = sides
    record = fungi / "double-compression-slowest-inplane-1.txt"
    cli(wagashi_bin, ["import", "rheometer", record, "--cylinder-radius-mm", "4", "-o", "bundles"], c)
    bundles = wagashi.import_records("rheometer", [record], "bundles", cylinder_radius_mm=4.0)
    assert bundles == [Path("bundles") / record.stem]
    assert_same_outputs(c / "bundles", p / "bundles")
    cli(wagashi_bin, ["fit", bundles[0], "--axisymmetric", "--starts", "1", "-o", "fit"], c)
    result = wagashi.fit(bundles[0], "fit", axisymmetric=True, starts=1)
    assert_same_outputs(c / "fit", p / "fit")
    assert result["trials"]
