"""wagashi.distributed on a 2-worker LocalCluster: the serial command line's
results, in input order, with a failing task reported and the others finished."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

distributed = pytest.importorskip("distributed")

import wagashi  # noqa: E402
from wagashi.distributed import TaskFailure, failures, fit_each, grid_points, press_sweep  # noqa: E402
from conftest import REPO, assert_same_outputs, cli, five_element_start, without_timings  # noqa: E402

MAT1_2D = REPO / "examples" / "paper" / "mat1-2d"


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=40
    )
    with distributed.Client(cluster) as c:
        yield c
    cluster.close()


def test_fit_each_equals_the_serial_cli_and_reports_a_failure(tmp_path, monkeypatch, client, wagashi_bin):
    # Three measured trials (the 2D trial at three stiffnesses), and one bundle
    # with nothing measured in the middle.
    trials = []
    for i, e1 in enumerate([0.03, 0.035, 0.04]):
        edited = wagashi.set_bundle_keys(MAT1_2D, tmp_path / f"src{i}", {"materials.mat1.E1_MPa": e1})
        cli(wagashi_bin, ["press", edited, "-o", tmp_path / f"trial{i}", "--size-mm", "10"], tmp_path)
        trials.append(tmp_path / f"trial{i}")
    bundles = [trials[0], trials[1], MAT1_2D, trials[2]]
    start = five_element_start(tmp_path / "start.toml")
    # Relative paths are the client's: the workers get them made absolute.
    monkeypatch.chdir(tmp_path)
    options = dict(materials="start.toml", size_mm=20.0, starts=1)

    results = fit_each(bundles, "campaign", client, **options)

    assert len(results) == 4
    bad = results[2]
    assert isinstance(bad, TaskFailure) and failures(results) == [bad]
    assert bad.input == str(MAT1_2D) and bad.error_type == "WagashiError"
    assert bad.message == f"{MAT1_2D / 'experiment.toml'}: has no measured data ([data] force or markers): nothing to fit"
    assert not Path(bad.output).exists()
    folders = sorted(p.name for p in (tmp_path / "campaign").iterdir())
    assert folders == ["0000-trial0", "0001-trial1", "0003-trial2"]
    for i, (bundle, result) in enumerate(zip(bundles, results)):
        if i == 2:
            continue
        serial = tmp_path / f"serial{i}"
        args = ["--materials", start, "--size-mm", "20", "--starts", "1"]
        cli(wagashi_bin, ["fit", bundle, "-o", serial, *args], tmp_path)
        expected = json.loads((serial / "fit.json").read_text())
        assert without_timings(result) == without_timings(expected), bundle
        task_out = tmp_path / "campaign" / f"{i:04d}-{bundle.name}"
        for name in ("fit.json", "materials.toml", "fit.svg", "shapes.svg"):
            a, b = (serial / name).read_bytes(), (task_out / name).read_bytes()
            assert a == b or without_timings(json.loads(a)) == without_timings(json.loads(b)), name
    # Each fit found its own trial's stiffness.
    e1 = [r["sets"]["force"]["mat1"]["E1_MPa"]["value"] for r in results if not isinstance(r, TaskFailure)]
    assert e1 == sorted(e1) and len(set(e1)) == 3


def test_press_sweep_equals_serial_presses_in_grid_order(tmp_path, client, wagashi_bin):
    grid = {"materials.mat1.E1_MPa": [0.03, -1.0, 0.05], "protocol.end_s": [300.0]}
    points = grid_points(grid)
    assert points[1] == {"materials.mat1.E1_MPa": -1.0, "protocol.end_s": 300.0}

    results = press_sweep(MAT1_2D, tmp_path / "sweep", client, grid, size_mm=10.0)

    assert [isinstance(r, TaskFailure) for r in results] == [False, True, False]
    bad = results[1]
    assert bad.input == points[1] and "E1_MPa" in bad.message and "experiment.toml" in bad.message
    for i in (0, 2):
        folder = tmp_path / "sweep" / f"{i:04d}"
        serial = tmp_path / f"serial{i}"
        cli(wagashi_bin, ["press", folder / "bundle", "-o", serial, "--size-mm", "10"], tmp_path)
        assert (serial / "force.csv").read_bytes() == (folder / "press" / "force.csv").read_bytes()
        expected = json.loads((serial / "summary.json").read_text())
        got = {k: v for k, v in results[i].items() if k not in ("force_t_s", "force_N")}
        expected["output"] = got["output"]
        assert without_timings(got) == without_timings(expected)
        assert results[i]["final_time_s"] == 300.0 and len(results[i]["force_N"]) == results[i]["force_samples"]
    assert results[2]["peak_force_N"] > results[0]["peak_force_N"]
    # The input bundle is never modified.
    assert "E1_MPa = 0.0349" in (MAT1_2D / "experiment.toml").read_text()


def test_a_list_grid_gives_its_points_and_a_bad_grid_is_refused():
    assert grid_points([{"a.b": 1}, {"a.b": 2, "c": None}]) == [{"a.b": 1}, {"a.b": 2, "c": None}]
    assert grid_points({"x": [1, 2], "y": [3, 4]}) == [
        {"x": 1, "y": 3},
        {"x": 1, "y": 4},
        {"x": 2, "y": 3},
        {"x": 2, "y": 4},
    ]
    with pytest.raises(wagashi.OptionError, match="list of values"):
        grid_points({"protocol.end_s": 300.0})
