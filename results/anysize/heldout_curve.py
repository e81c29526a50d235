"""Held-out learning curves of set-policy runs: every checkpoint of each run flies the same
validation priors (seeds 5000-5019 by default: the validation stream of docs/BENCHMARKS.md,
never the test seeds 1000-1049 nor this issue's evaluation stream 28000-28049) on each task,
and the mean POSC per checkpoint is written to CSV and plotted. The curves select the shipped
checkpoint; the evaluation stream only scores it.

    python results/anysize/heldout_curve.py runs/anysize_s1 --every 4 \
        --out results/anysize/heldout

Appends to ``OUT/curve.csv`` (a (run, step, task, seed) already there is not flown again), so
it can run while training goes on and pick up new checkpoints. Without run folders it only
re-plots ``OUT/curve.csv`` (several runs: each a thin line, their mean a thick one).
"""

from __future__ import annotations

import argparse
import csv
import io
import re
from pathlib import Path

import numpy as np

from poc_env.agents.experiments.evaluate import run_episode
from poc_env.io import write_text_atomic
from poc_env.tasks import get_task

TASKS = {
    "paper62": "UAVSearch-Paper62-Random-Set-Heading-v1",
    "wide_n6": "UAVSearch-Wide-N6-Random-Set-Heading-v1",
    "wide_n12": "UAVSearch-Wide-N12-Random-Set-Heading-v1",
    "wide_n24": "UAVSearch-Wide-N24-Random-Set-Heading-v1",
    "paper62_inc": "UAVSearch-Paper62-Random-Increments-v0",  # results/bc_increments
}
FIELDS = ["run", "step", "task", "seed", "posc"]


def checkpoints(run: Path) -> list[tuple[int, Path]]:
    out = []
    for p in (run / "checkpoints").glob("step_*.zip"):
        m = re.fullmatch(r"step_(\d+)\.zip", p.name)
        if m:
            out.append((int(m.group(1)), p))
    return sorted(out)


def reference(text: str) -> tuple[str, float]:
    """``NAME=POSC`` of ``--reference``: a name and a POSC in [0, 1] (else argparse's error,
    naming the option and the value)."""
    name, _, value = text.partition("=")
    try:
        posc = float(value)
    except ValueError:
        posc = float("nan")
    if not name or not (0.0 <= posc <= 1.0):
        raise argparse.ArgumentTypeError(f"got {text!r}; allowed: NAME=POSC, POSC in [0, 1]")
    return name, posc


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument(
        "runs", nargs="*", type=Path, help="run folders (none: only re-plot OUT/curve.csv)"
    )
    ap.add_argument("--tasks", default=",".join(TASKS), help="keys of " + ", ".join(TASKS))
    ap.add_argument("--every", type=int, default=1, help="every k-th checkpoint (and the last)")
    ap.add_argument("--seed", type=int, default=5000)
    ap.add_argument("--episodes", type=int, default=20)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument(
        "--reference", action="append", default=[], metavar="NAME=POSC", type=reference,
        help="a dashed line at a planner's mean POSC on the same priors (repeatable)",
    )  # fmt: skip
    a = ap.parse_args()
    refs = a.reference
    a.out.mkdir(parents=True, exist_ok=True)
    path = a.out / "curve.csv"
    rows: list[dict[str, str]] = []
    if path.is_file():
        rows = list(csv.DictReader(path.open(newline="")))
    done = {(r["run"], r["step"], r["task"], r["seed"]) for r in rows}
    for run in a.runs:
        ck = checkpoints(run)
        pick = [c for k, c in enumerate(ck) if k % a.every == a.every - 1 or k == len(ck) - 1]
        for step, model in pick:
            for key in a.tasks.split(","):
                sc = get_task(TASKS[key]).load_scenario()
                for seed in range(a.seed, a.seed + a.episodes):
                    if (run.name, str(step), key, str(seed)) in done:
                        continue
                    ep = run_episode(sc, f"ppo:{model}", seed, random_priors=True)
                    rows.append({"run": run.name, "step": str(step), "task": key,
                                 "seed": str(seed), "posc": f"{ep.posc:.6f}"})  # fmt: skip
                buf = io.StringIO()
                w = csv.DictWriter(buf, fieldnames=FIELDS, lineterminator="\n")
                w.writeheader()
                w.writerows(rows)
                write_text_atomic(path, buf.getvalue())  # after each (checkpoint, task)
                here = (run.name, str(step), key)
                got = [float(r["posc"]) for r in rows if (r["run"], r["step"], r["task"]) == here]
                print(f"{run.name} {step:>9} {key:<9} {np.mean(got):.4f} ({len(got)} priors)")
    plot(rows, a.out / "curve.png", refs)


def method(run: str) -> str:
    """The recipe a run folder belongs to: its name less a trailing ``_s<seed>``."""
    return re.sub(r"_s\d+$", "", run)


def plot(
    rows: list[dict[str, str]], out: Path, refs: list[tuple[str, float]] | None = None
) -> None:
    """One colour per task and recipe (:func:`method`): each run a thin line, the mean over the
    recipe's runs a thick one (at the checkpoints every run has)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    groups = sorted({(r["task"], method(r["run"])) for r in rows})
    for k, (task, recipe) in enumerate(groups):
        colour = f"C{k}"
        runs = sorted({r["run"] for r in rows if (r["task"], method(r["run"])) == (task, recipe)})
        curves = {}
        for run in runs:
            steps = sorted({int(r["step"]) for r in rows if (r["run"], r["task"]) == (run, task)})
            here = [r for r in rows if (r["run"], r["task"]) == (run, task)]
            curves[run] = {
                s: float(np.mean([float(r["posc"]) for r in here if r["step"] == str(s)]))
                for s in steps
            }
            if len(runs) > 1:
                ax.plot(np.array(steps) / 1e6, [curves[run][s] for s in steps], color=colour,
                        lw=0.8, alpha=0.35)  # fmt: skip
        common = sorted(set.intersection(*(set(c) for c in curves.values() if c)))
        mean = [np.mean([curves[run][s] for run in runs if curves[run]]) for s in common]
        label = f"{runs[0]}: {task}"
        if len(runs) > 1:
            label = f"{recipe}: {task} (mean of {len(runs)} runs)"
        ax.plot(np.array(common) / 1e6, mean, color=colour, lw=2, marker="o", label=label)
    for name, value in refs or []:
        ax.axhline(value, color="k", ls="--", lw=1, label=f"{name} (same priors)")
    ax.set_xlabel("PPO agent transitions (M)")
    ax.set_ylabel("mean POSC, validation priors")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    main()
