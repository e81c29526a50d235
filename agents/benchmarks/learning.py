"""Sample efficiency: held-out learning curves of training runs, seeds side by side.

    poc-env bench learning --recipe LABEL=RUN[,RUN...] [--recipe ...] [--reference de_plan]
                           [--episodes 20] [--seed 5000] [--workers K] [--out DIR]

Every checkpoint of every run (``checkpoints/step_*.zip`` of ``poc-env train``, kept with
``--keep-checkpoints 0``) is flown deterministically on the same ``--episodes`` held-out
episodes of the run's task (:func:`poc_env.agents.experiments.evaluate.evaluate`: seeds ``--seed
..``, on ``-Random-`` tasks each seed's own prior from the evaluation stream training never draws
from), and so is the ``--reference`` policy (default ``de_plan``, the paper's planner). This
measures the curve on unseen maps, not the training episodes' POSC SB3 logs.

Per run it reports the agent transitions and the wall time (the checkpoint file's time minus
the run's ``config.json`` time: one core per run, on a machine possibly shared with other
jobs) at the first checkpoint whose held-out mean POSC reaches the reference's mean, and the
last checkpoint's POSC; per recipe the mean and the spread (min, max) over its runs (seeds).

Writes into ``--out`` as one set (both or none of ``learning.csv``: one row per run and
checkpoint, and ``learning.md``: the summary table) plus ``learning.png``: each recipe's mean
curve with its min-max band over seeds, the reference as a line.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import numpy as np

from poc_env.errors import ConfigError
from poc_env.helptext import HelpFormatter, examples
from poc_env.io import read_json


def build_parser() -> argparse.ArgumentParser:
    """This benchmark's command line (``--help``: options, defaults, examples)."""
    p = argparse.ArgumentParser(
        formatter_class=HelpFormatter,
        epilog=examples(
            "poc-env bench learning --recipe heading=runs/s0,runs/s1 --episodes 5 --every 2"
        ),
        prog="poc-env bench learning",
        description=__doc__.split("\n")[0],
    )
    p.add_argument(
        "--recipe",
        action="append",
        default=[],
        metavar="LABEL=RUN[,RUN...]",
        help="a recipe's runs (one per seed), e.g. heading=runs/s0,runs/s1,runs/s2",
    )
    p.add_argument("--reference", default="de_plan", help="policy whose mean POSC is the bar")
    p.add_argument("--episodes", type=int, default=20)
    p.add_argument("--seed", type=int, default=5000, help="first held-out episode seed")
    p.add_argument("--workers", type=int, default=1)
    p.add_argument("--every", type=int, default=1, help="evaluate every k-th checkpoint")
    p.add_argument("--out", default=None, help="folder for learning.csv, .md and .png")
    p.add_argument("--quiet", action="store_true")
    return p


def _parse(argv: list[str] | None) -> argparse.Namespace:
    return build_parser().parse_args(argv)


def checkpoints(run: Path) -> list[tuple[int, Path]]:
    """``(step, path)`` of a run's ``checkpoints/step_*.zip``, by step."""
    out = []
    for f in (run / "checkpoints").glob("step_*.zip"):
        try:
            out.append((int(f.stem.split("_", 1)[1]), f))
        except ValueError:
            continue
    return sorted(out)


def _task(run: Path) -> str:
    cfg = run / "config.json"
    try:
        task = read_json(cfg, "recipe").get("task")
    except (ValueError, AttributeError):  # ConfigError (unreadable, not JSON) is a ValueError
        task = None
    if not task:
        raise ConfigError("recipe", str(run), "a run folder of poc-env train --task (config.json)")
    return str(task)


def _recipes(items: list[str]) -> dict[str, list[Path]]:
    out: dict[str, list[Path]] = {}
    for item in items:
        label, sep, runs = item.partition("=")
        paths = [Path(r) for r in runs.split(",") if r.strip()]
        if not sep or not label or not paths:
            raise ConfigError("recipe", item, "LABEL=RUN[,RUN...] (run folders of poc-env train)")
        for r in paths:
            if not checkpoints(r):
                raise ConfigError(
                    "recipe", str(r), "a run folder with checkpoints/step_*.zip (train with "
                    "--keep-checkpoints 0 to keep every one)",
                )  # fmt: skip
        out[label] = paths
    if not out:
        raise ConfigError("recipe", None, "at least one --recipe LABEL=RUN[,RUN...]")
    return out


def run(args: argparse.Namespace) -> tuple[list[dict[str, Any]], list[dict[str, Any]], float]:
    """(rows per run and checkpoint, summary rows per run and recipe, the reference's mean)."""
    from poc_env.agents.experiments.evaluate import check_policies, evaluate
    from poc_env.tasks import get_task

    recipes = _recipes(args.recipe)
    check_policies([args.reference])
    tasks = {_task(r) for runs in recipes.values() for r in runs}
    if len(tasks) != 1:
        raise ConfigError("recipe", sorted(tasks), "runs of one task (one held-out episode set)")
    task = get_task(tasks.pop())
    kw = {
        "episodes": args.episodes,
        "seed0": args.seed,
        "workers": args.workers,
        "random_priors": task.random_prior,
    }
    sc = task.load_scenario()  # the task itself: a size task's fleet, a Drift task's target
    ref = evaluate(sc, [args.reference], **kw).rows()[0]["posc_mean"]
    rows: list[dict[str, Any]] = []
    summary: list[dict[str, Any]] = []
    for label, runs in recipes.items():
        per_run = []
        for r in runs:
            start = (r / "config.json").stat().st_mtime
            cks = checkpoints(r)
            cks = [c for k, c in enumerate(cks) if k % args.every == 0 or k == len(cks) - 1]
            for step, path in cks:
                ev = evaluate(sc, [f"ppo:{path}"], **kw).rows()[0]
                rows.append(
                    {
                        "recipe": label,
                        "run": str(r),
                        "step": step,
                        "wall_s": round(path.stat().st_mtime - start),
                        "posc_mean": ev["posc_mean"],
                        "posc_ci95": ev["posc_ci95"],
                        "normalised": ev["normalised"],
                    }
                )
                if not args.quiet:
                    print(f"{label} {r} step {step}: {ev['posc_mean']:.4f}", file=sys.stderr)
            per_run.append(
                run_summary([x for x in rows if x["run"] == str(r) and x["recipe"] == label], ref)
            )
        summary.extend(per_run)
        summary.append(_spread(label, per_run))
    return rows, summary, float(ref)


def run_summary(curve: list[dict[str, Any]], ref: float) -> dict[str, Any]:
    """One run's row from its checkpoints' rows (by step): the first checkpoint whose mean
    POSC reaches ``ref`` (its step and wall time, None if none does), the last and the best."""
    hit = next((x for x in curve if x["posc_mean"] >= ref), None)
    return {
        "recipe": curve[-1]["recipe"],
        "run": curve[-1]["run"],
        "steps_to_reference": None if hit is None else hit["step"],
        "wall_s_to_reference": None if hit is None else hit["wall_s"],
        "final_step": curve[-1]["step"],
        "final_posc": curve[-1]["posc_mean"],
        "best_posc": max(x["posc_mean"] for x in curve),
    }


def _spread(label: str, per_run: list[dict[str, Any]]) -> dict[str, Any]:
    """The recipe's row: mean [min, max] over its runs (None when a run never reached)."""

    def agg(key: str) -> str | None:
        vals = [r[key] for r in per_run]
        if any(v is None for v in vals):
            return f"{sum(v is not None for v in vals)}/{len(vals)} runs reached"
        a = np.asarray(vals, dtype=float)
        return f"{a.mean():.4g} [{a.min():.4g}, {a.max():.4g}]"

    return {
        "recipe": label,
        "run": f"mean [min, max] of {len(per_run)} runs",
        **{
            k: agg(k)
            for k in (
                "steps_to_reference",
                "wall_s_to_reference",
                "final_step",
                "final_posc",
                "best_posc",
            )
        },
    }


def to_markdown(summary: list[dict[str, Any]], reference: str, ref: float, command: str) -> str:
    head = (
        "| recipe | run | transitions to reach "
        f"{reference} | wall s to reach | final step | final POSC | best POSC |"
    )
    lines = [
        f"Held-out mean POSC of `{reference}` (the bar): {ref:.4f}. Command: `{command}`",
        "",
        head,
        "|---|---|---|---|---|---|---|",
    ]

    def cell(v: Any) -> str:
        if v is None:
            return "not reached"
        if isinstance(v, float):
            return f"{v:.4f}"
        return str(v)

    for r in summary:
        lines.append(
            f"| {r['recipe']} | {r['run']} | {cell(r['steps_to_reference'])} | "
            f"{cell(r['wall_s_to_reference'])} | {cell(r['final_step'])} | "
            f"{cell(r['final_posc'])} | {cell(r['best_posc'])} |"
        )
    return "\n".join(lines) + "\n"


def plot(rows: list[dict[str, Any]], reference: str, ref: float, path: Path) -> Path:
    """Each recipe's mean held-out POSC over transitions with its min-max band over runs."""
    from poc_env.viz.plots import _figure, save_figure_atomic

    fig = _figure((7.0, 4.2))
    ax = fig.add_subplot()
    for k, label in enumerate(dict.fromkeys(r["recipe"] for r in rows)):
        mine = [r for r in rows if r["recipe"] == label]
        runs = list(dict.fromkeys(r["run"] for r in mine))
        curves = [
            np.array([(r["step"], r["posc_mean"]) for r in mine if r["run"] == run]) for run in runs
        ]
        grid = np.unique(np.concatenate([c[:, 0] for c in curves]))
        grid = grid[grid <= min(c[-1, 0] for c in curves)]  # steps every run reached
        ys = np.array([np.interp(grid, c[:, 0], c[:, 1]) for c in curves])
        colour = f"C{k}"
        for c in curves:
            ax.plot(c[:, 0] / 1e6, c[:, 1], color=colour, lw=0.6, alpha=0.4)
        ax.plot(grid / 1e6, ys.mean(axis=0), color=colour, lw=2, label=f"{label} ({len(runs)})")
        ax.fill_between(grid / 1e6, ys.min(axis=0), ys.max(axis=0), color=colour, alpha=0.15)
    ax.axhline(ref, color="k", ls="--", lw=1, label=reference)
    ax.set_xlabel("agent transitions (millions)")
    ax.set_ylabel("held-out mean POSC")
    ax.set_title("Learning curves on unseen priors (mean, min-max over seeds)")
    ax.legend()
    return save_figure_atomic(fig, path)


def main(argv: list[str] | None = None) -> list[dict[str, Any]]:
    import shlex

    from poc_env.agents.benchmarks import check_counts, write_table_set
    from poc_env.io import check_out

    args = _parse(argv)
    check_out("out", args.out, "folder")  # before the run, not after it
    check_counts(args, episodes=1, seed=0, workers=1, every=1)
    given = sys.argv[1:] if argv is None else argv
    command = "poc-env bench learning " + shlex.join(given)
    rows, summary, ref = run(args)
    md = to_markdown(summary, args.reference, ref, command.strip())
    print(md)
    if args.out:  # the three files or none
        figure = lambda path: plot(rows, args.reference, ref, path)  # noqa: E731
        write_table_set(args.out, "learning", rows, md, figure)
    return summary


if __name__ == "__main__":
    from poc_env.agents.benchmarks import run_main

    run_main(main)
