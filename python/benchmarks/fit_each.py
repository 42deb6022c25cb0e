"""fit_each on a 2-worker LocalCluster against the binary run once per trial,
and the cost of the Python layer on one press.

    python python/benchmarks/fit_each.py [--binary target/release/wagashi] [--repeat 3]

The 6 trials: the shared fungi-steak double compressions (three records, the
first and the second stroke of each), imported with `wagashi import rheometer
--cylinder-radius-mm 4 [--stroke 2]`, each fitted with `--axisymmetric`
(default starts). Without ../shared/data, 6 synthetic 2D trials instead (the
seed's material 1 in 2D at six stiffnesses, fitted at 5 mm). Each figure is the
median of `--repeat` runs of the whole set; the load average is printed with
them (the machine may be shared).

The press: `examples/paper/mat1` at `--size-mm 4` (3D), `wagashi.press`
against the binary, median of `--repeat` runs each.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def trials(work: Path, binary: Path) -> tuple[list, list, str]:
    """The 6 bundles, the fit options, and what they are."""
    fungi = Path(os.environ.get("WAGASHI_SHARED_DATA", REPO.parent / "shared" / "data")) / "real" / "fungi-steak"
    records = sorted(fungi.glob("double-compression-slowest-inplane-*.txt"))
    if len(records) == 3:
        bundles = []
        for stroke in ("1", "2"):
            out = work / f"stroke{stroke}"
            args = [binary, "import", "rheometer", *records, "--cylinder-radius-mm", "4", "--stroke", stroke, "-o", out]
            subprocess.run(list(map(str, args)), check=True, capture_output=True)
            bundles += [out / r.stem for r in records]
        return bundles, ["--axisymmetric"], "the fungi-steak records, strokes 1 and 2, axisymmetric, default starts"
    import wagashi

    start = work / "start.toml"
    start.write_text('[materials.mat1]\nmodel = "five-element"\n')
    bundles = []
    for i, e1 in enumerate([0.025, 0.03, 0.035, 0.04, 0.045, 0.05]):
        src = wagashi.set_bundle_keys(REPO / "examples/paper/mat1-2d", work / f"src{i}", {"materials.mat1.E1_MPa": e1})
        subprocess.run([str(binary), "press", str(src), "-o", str(work / f"t{i}"), "--size-mm", "5"], check=True, capture_output=True)
        bundles.append(work / f"t{i}")
    return bundles, ["--materials", str(start), "--size-mm", "5"], "synthetic 2D trials (mat1-2d at six E1), 5 mm"


def to_options(args: list) -> dict:
    options, i = {}, 0
    while i < len(args):
        name = args[i].lstrip("-").replace("-", "_")
        if i + 1 < len(args) and not args[i + 1].startswith("--"):
            options[name] = args[i + 1]
            i += 2
        else:
            options[name] = True
            i += 1
    return options


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    parser.add_argument("--binary", type=Path, default=Path(os.environ.get("WAGASHI_BIN", target / "release" / "wagashi")))
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    import wagashi
    from distributed import Client, LocalCluster
    from wagashi.distributed import failures, fit_each

    work = Path(tempfile.mkdtemp(prefix="wagashi-bench-"))
    try:
        bundles, fit_args, what = trials(work, args.binary)
        print(f"trials: {len(bundles)}, {what}")
        print(f"load average at the start: {os.getloadavg()}")

        serial = []
        for r in range(args.repeat):
            t0 = time.perf_counter()
            for i, b in enumerate(bundles):
                out = work / f"cli-{r}-{i}"
                subprocess.run([str(args.binary), "fit", str(b), "-o", str(out), *fit_args], check=True, capture_output=True)
            serial.append(time.perf_counter() - t0)

        with LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None) as cluster, Client(cluster) as client:
            client.run(lambda: __import__("wagashi"))  # import once per worker, outside the timing
            distributed = []
            for r in range(args.repeat):
                t0 = time.perf_counter()
                results = fit_each(bundles, work / f"dask-{r}", client, **to_options(fit_args))
                distributed.append(time.perf_counter() - t0)
                assert not failures(results), failures(results)

        s, d = statistics.median(serial), statistics.median(distributed)
        print(f"binary one by one: {s:.2f} s (runs {[round(x, 2) for x in serial]})")
        print(f"fit_each, 2-worker LocalCluster: {d:.2f} s (runs {[round(x, 2) for x in distributed]})")
        print(f"speed-up: {s / d:.2f}x")

        mat1 = REPO / "examples" / "paper" / "mat1"
        cli_press, py_press = [], []
        for r in range(args.repeat):
            t0 = time.perf_counter()
            subprocess.run([str(args.binary), "press", str(mat1), "-o", str(work / f"pc{r}"), "--size-mm", "4"], check=True, capture_output=True)
            cli_press.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            wagashi.press(mat1, work / f"pp{r}", size_mm=4.0)
            py_press.append(time.perf_counter() - t0)
        c, p = statistics.median(cli_press), statistics.median(py_press)
        print(f"press examples/paper/mat1 --size-mm 4: binary {c:.3f} s, wagashi.press {p:.3f} s: {100 * (p / c - 1):+.1f} %")
        print(f"load average at the end: {os.getloadavg()}")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
