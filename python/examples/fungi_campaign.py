# %% [markdown]
# # The fungi-steak records, from Python
#
# What it shows: the shared fungi-steak double compressions (a texture
# analyser's raw exports) imported into bundles, the five-element model fitted
# to each specimen's first stroke on a Dask cluster, measured against simulated
# force plotted with matplotlib, and a press-speed sweep on the same cluster.
#
# How to run it (after `pip install ./python` and
# `pip install "dask[distributed]" matplotlib`), from the repository:
#
#     python python/examples/fungi_campaign.py [OUT]
#
# OUT (default `fungi-campaign`) is created; the records are read from
# `../shared/data/real/fungi-steak` beside the repository (or
# `$WAGASHI_SHARED_DATA/real/fungi-steak`) and never copied into it. Without
# them the example says so and stops (on CI, with `CI` set, it fails instead).
# Each cell below runs as it is in a notebook.

# %% 1. The records
import os
import sys
import tomllib
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only: no display needed
import matplotlib.pyplot as plt
import numpy as np
from distributed import Client, LocalCluster

import wagashi
from wagashi.distributed import failures, fit_each, press_sweep

REPO = Path(__file__).resolve().parents[2]
shared = Path(os.environ.get("WAGASHI_SHARED_DATA", REPO.parent / "shared" / "data"))
records_dir = shared / "real" / "fungi-steak"
if not records_dir.is_dir():
    message = f"the fungi-steak records are missing at {records_dir}"
    if os.environ.get("CI", "") not in ("", "false", "0"):
        sys.exit(f"error: {message}; on CI they must be there")
    print(f"skipped: {message}")
    sys.exit(0)
records = sorted(records_dir.glob("double-compression-slowest-inplane-*.txt"))
out = Path(sys.argv[1] if len(sys.argv) > 1 else "fungi-campaign")
out.mkdir(parents=True, exist_ok=True)
print(f"{len(records)} records in {records_dir}")

# %% 2. Import: the first stroke of each record as a cylinder bundle (punched to 8 mm)
bundles = wagashi.import_records("rheometer", records, out / "bundles", cylinder_radius_mm=4.0, force=True)
for b in bundles:
    print("bundle", b)

# %% 3. Fit each specimen on a 2-worker LocalCluster (one task per bundle, one thread per task).
# The workers are threads of this process (processes=False: no `if __name__ ==
# "__main__"` guard needed, as in a notebook); wagashi releases the GIL while it
# runs, so the two tasks run at once.
cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None)
client = Client(cluster)
fits = fit_each(bundles, out / "fits", client, axisymmetric=True, starts=1, force=True)
assert not failures(fits), failures(fits)
for bundle, fit in zip(bundles, fits):
    # The imported bundles name their material "sample" (`wagashi import --material`).
    e1 = fit["sets"]["force"]["sample"]["E1_MPa"]
    print(f"{bundle.name}: E1 = {e1['value']:.4g} MPa, 95 % interval {e1['ci95']}")

# %% 4. Measured against simulated force, specimen by specimen
fig, ax = plt.subplots(figsize=(7, 4.5))
for i, bundle in enumerate(bundles):
    fitted = out / "fits" / f"{i:04d}-{bundle.name}" / "materials.toml"
    run = wagashi.press(bundle, out / f"press-{bundle.name}", materials=fitted, axisymmetric=True, force=True)
    measured = np.loadtxt(bundle / "force.csv", delimiter=",", skiprows=1)
    (line,) = ax.plot(measured[:, 0], measured[:, 1], ".", ms=2, label=f"{bundle.name[-1]}: measured")
    ax.plot(run.force["t_s"], run.force["force_N"], "-", color=line.get_color(), label=f"{bundle.name[-1]}: simulated")
    print(f"{bundle.name}: simulated - measured rms {run['force_rms_diff_N']:.4f} N of peak {run['peak_force_N']:.3f} N")
ax.set_xlabel("t [s]")
ax.set_ylabel("force [N]")
ax.set_title("fungi steak, first stroke: measured and fitted five-element model")
ax.legend(fontsize=7, ncol=2)
fig.tight_layout()
fig.savefig(out / "measured-vs-simulated.png", dpi=120)
print("plot", out / "measured-vs-simulated.png")

# %% 5. A press-speed sweep of specimen 1 with its fitted material: the protocol's
# times divided by the speed factor, the measured data dropped (nothing to compare).
experiment = tomllib.loads((bundles[0] / "experiment.toml").read_text())
protocol = experiment["protocol"]
grid = []
for factor in (0.5, 1.0, 2.0, 4.0):
    grid.append(
        {
            "protocol.waypoints": [[t / factor, d] for t, d in protocol["waypoints"]],
            "protocol.release_s": protocol["release_s"] / factor,
            "protocol.end_s": protocol["end_s"] / factor,
            "data": None,
        }
    )
fitted = (out / "fits" / f"0000-{bundles[0].name}" / "materials.toml").resolve()
sweep = press_sweep(bundles[0], out / "sweep", client, grid, materials=fitted, axisymmetric=True, force=True)
assert not failures(sweep), failures(sweep)
for factor, run in zip((0.5, 1.0, 2.0, 4.0), sweep):
    print(f"speed x{factor}: peak force {run['peak_force_N']:.4f} N, final height loss {run['final_height_loss_mm']:.4f} mm")
peaks = [run["peak_force_N"] for run in sweep]
# A viscoelastic specimen resists a faster press more.
assert peaks == sorted(peaks), peaks

client.close()
cluster.close()
