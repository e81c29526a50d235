"""Training curves (rollout/posc_mean: the mean POSC of the last 100 training episodes) of the
Drift runs on one figure, with the planners' evaluation-stream means (``evaluate.csv`` beside
this file) as lines, and each run's wall-clock rate between its first and last checkpoint (the
machine was shared: the rates depend on the load, see README.md).

    PYTHONPATH=. python results/drift_learned/curves.py runs/drift_res_receding_s1 \
        runs/drift_res_receding_s2 runs/drift_scratch_s1
"""

import csv
import sys
from pathlib import Path

import numpy as np

from poc_env.agents.rl.checkpoint import checkpoint_steps
from poc_env.agents.rl.curve import training_curve
from poc_env.viz.plots import _figure, save_figure_atomic

out = Path(__file__).parent
fig = _figure((7.0, 4.0))
ax = fig.add_subplot()
rows = ["run,first_checkpoint,last_checkpoint,seconds,transitions_per_second"]
for i, run in enumerate(map(Path, sys.argv[1:])):
    d = training_curve(run)["rollout/posc_mean"]
    k = max(1, len(d) // 40)
    smooth = np.convolve(d[:, 1], np.ones(k) / k, mode="valid")
    ax.plot(d[:, 0] / 1e6, d[:, 1], lw=0.6, alpha=0.3, color=f"C{i}")
    ax.plot(d[k - 1 :, 0] / 1e6, smooth, lw=2, color=f"C{i}", label=run.name)
    steps = checkpoint_steps(run)
    if len(steps) >= 2:
        t = [(run / "checkpoints" / f"step_{s}.zip").stat().st_mtime for s in (steps[0], steps[-1])]
        rate = (steps[-1] - steps[0]) / (t[1] - t[0])
        rows.append(f"{run.name},{steps[0]},{steps[-1]},{t[1] - t[0]:.0f},{rate:.0f}")
with (out / "evaluate.csv").open(encoding="utf-8") as f:
    planners = {r["policy"]: float(r["posc_mean"]) for r in csv.DictReader(f)}
for j, name in enumerate(("spacetime_receding", "spacetime_plan", "allocation_plan")):
    if name in planners:
        ax.axhline(planners[name], color="k", ls=("--", ":", "-.")[j], lw=1,
                   label=f"{name} (evaluation stream)")  # fmt: skip
ax.set_xlabel("PPO agent transitions (millions)")
ax.set_ylabel("POSC of recent training episodes")
ax.set_title("UAVSearch-Small-Drift-Heading-v1")
ax.legend(fontsize=7)
save_figure_atomic(fig, out / "curves.png")
(out / "throughput.csv").write_text("\n".join(rows) + "\n")
print("\n".join(rows))
