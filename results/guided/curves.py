"""Training curves (rollout/posc_mean) of the planner-guided runs on one figure, and each run's
wall-clock training rate between its first and last checkpoint (the machine was shared: the
rates depend on the load, see docs/rl.md).

    PYTHONPATH=. python results/guided/curves.py runs/scratch_s1 runs/bc_s1 runs/residual_s1
"""

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
ax.axhline(0.6931, color="k", ls="--", lw=1, label="allocation_plan (evaluation stream)")
ax.set_xlabel("PPO agent transitions (millions)")
ax.set_ylabel("POSC of recent training episodes")
ax.set_title("UAVSearch-Paper62-Random-Set-Heading-v1, seed 1")
ax.legend(fontsize=8)
save_figure_atomic(fig, out / "curves.png")
(out / "throughput.csv").write_text("\n".join(rows) + "\n")
print("\n".join(rows))
