"""The baseline table: every registered task x the classical and learned baselines.

    poc-env bench baselines [--tasks ID ...] [--episodes 20] [--policies ...] [--out DIR]
                            [--workers K | --ray [ADDRESS]] [--quick]

Each task is scored with :func:`poc_env.agents.experiments.evaluate.evaluate` on the same seeds for
every policy (seeds ``--seed .. --seed + episodes - 1``; on ``-Random-`` tasks each seed flies
its own held-out prior, :func:`~poc_env.agents.experiments.evaluate.episode_prior`, a generator
stream training never draws from). Columns: mean POSC with its 95 % interval over the seeds
(Student's t, :func:`poc_env.stats.ci95`), POSC normalised by each episode's reach-aware bound
(:func:`poc_env.theory.bound.reach_effort_bound`: the best POSC any swarm could reach with
transit from its airfields at top speed), and the mean constraint-violation steps.

Policies per task (``--policies`` overrides):

- the floor at the task's control level: ``random`` (increments), ``random_heading`` or
  ``random_waypoint``;
- the classical planners ``lawnmower``, ``greedy_bayes``, ``de_plan`` (the paper's DE,
  faithful preset) and ``allocation_plan``: they command eq. 19 increments themselves, so they
  fly the same on a task's three control levels (scored once per scenario and prior, shown on
  each row);
- learned: ``--learned LABEL=POLICY`` adds a column ``LABEL`` flown by ``POLICY`` (a
  ``ppo:PATH`` or ``rllib:PATH`` spelling) on every task; ``{Control}`` in ``POLICY`` becomes
  the task's control part (``Heading`` ...), so one option names a run per control level, and
  ``LABEL@Heading=POLICY`` restricts the column to that control level's tasks.

Writes ``baselines.csv`` (one row per task and policy) and ``baselines.md`` (the table of
docs/tasks.md) into ``--out``, both or neither. ``--quick``: 2 episodes on the Small tasks only.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from poc_env.errors import ConfigError
from poc_env.helptext import HelpFormatter, examples

CLASSICAL = ("lawnmower", "greedy_bayes", "de_plan", "allocation_plan")
FLOOR = {"increments": "random", "heading": "random_heading", "waypoint": "random_waypoint"}


def build_parser() -> argparse.ArgumentParser:
    """This benchmark's command line (``--help``: options, defaults, examples)."""
    p = argparse.ArgumentParser(
        formatter_class=HelpFormatter,
        epilog=examples(
            "poc-env bench baselines --quick",
            "poc-env bench baselines --tasks poc_env/UAVSearch-Small-Heading-v1 --episodes 5",
        ),
        prog="poc-env bench baselines",
        description=__doc__.split("\n")[0],
    )
    p.add_argument("--tasks", nargs="*", default=None, help="task ids (default: every task)")
    p.add_argument("--episodes", type=int, default=None, help="episodes per task (default 20)")
    p.add_argument("--seed", type=int, default=1000, help="first episode seed")
    p.add_argument("--policies", default=None, help="comma-separated: replaces the default set")
    p.add_argument(
        "--learned",
        action="append",
        default=[],
        metavar="LABEL[@Control]=POLICY",
        help="a learned policy column, e.g. PPO-RLlib=rllib:runs/rllib_{Control} or "
        "pilot@Heading=ppo:ppo_pilot_paper_6_2",
    )
    p.add_argument("--workers", type=int, default=1)
    p.add_argument("--ray", nargs="?", const="local", default=None, metavar="ADDRESS")
    p.add_argument("--out", default=None, help="folder for baselines.csv and baselines.md")
    p.add_argument("--quick", action="store_true", help="2 episodes, Small tasks only")
    return p


def _parse(argv: list[str] | None) -> argparse.Namespace:
    return build_parser().parse_args(argv)


def run(args: argparse.Namespace) -> list[dict[str, Any]]:
    """Rows (task, policy, posc_mean, posc_ci95, normalised, violation_steps, episodes)."""
    from poc_env import tasks
    from poc_env.agents.experiments.evaluate import evaluate

    ids = args.tasks or [t for t in tasks.TASKS if not args.quick or "-Small-" in t]
    chosen = [tasks.get_task(t) for t in ids]
    if args.quick and args.episodes is not None:  # --quick fixes it (cli-audit: was replaced)
        raise ConfigError(
            "episodes", args.episodes, "absent with --quick (which flies 2 episodes a task); "
            "leave --quick out to fly this many",
        )  # fmt: skip
    episodes = 2 if args.quick else (20 if args.episodes is None else args.episodes)
    learned: list[tuple[str, str | None, str]] = []
    controls = {v: k for k, v in tasks.CONTROL_NAMES.items()}
    for item in args.learned:
        head, sep, pol = item.partition("=")
        label, at, only = head.partition("@")
        if not sep or not pol or not label or (at and only not in tasks.CONTROL_NAMES):
            raise ConfigError(
                "learned", item, "LABEL=POLICY or LABEL@Control=POLICY (Control: "
                + ", ".join(tasks.CONTROL_NAMES) + "), e.g. PPO-RLlib=rllib:runs/r_{Control}",
            )  # fmt: skip
        learned.append((label, only or None, pol))
    fixed = [p.strip() for p in (args.policies or "").split(",") if p.strip()] or None
    cache: dict[tuple[str, int | None, bool, str, str], dict[str, Any]] = {}
    rows = []
    for task in chosen:
        names = list(fixed) if fixed else [FLOOR[task.control], *CLASSICAL]
        labels = dict.fromkeys(names, "")
        for label, only, pol in learned:
            if only is None or tasks.CONTROL_NAMES[only] == task.control:
                spelled = pol.replace("{Control}", controls[task.control])
                names.append(spelled)
                labels[spelled] = label
        key = (task.scenario, task.n_uavs, task.random_prior, task.motion)  # what it flies
        todo = [n for n in names if (*key, n) not in cache]
        if todo:
            ev = evaluate(
                task.load_scenario(),  # a fleet-size task's fleet
                todo,
                episodes=episodes,
                seed0=args.seed,
                workers=args.workers,
                random_priors=task.random_prior,
            )
            for r in ev.rows():
                cache[(*key, r["policy"])] = r
        for n in names:
            r = cache[(*key, n)]
            rows.append(
                {
                    "task": task.id,
                    "policy": n,
                    "label": labels.get(n) or n,
                    "episodes": r["episodes"],
                    "posc_mean": r["posc_mean"],
                    "posc_ci95": r["posc_ci95"],
                    "normalised": r["normalised"],
                    "violation_steps": r["violation_steps"],
                    "bound_reach": r["bound_reach"],
                }
            )
        print(f"{task.id}: done", file=sys.stderr, flush=True)
    return rows


def _column(row: dict[str, Any]) -> str:
    """A row's column: its label; the unlabelled floor of each task's control level shares
    ``random``, and another level's floor flown on it (``--policies``) is named with its level,
    ``random_heading (heading)``."""
    from poc_env import tasks

    if row["label"] != row["policy"] or row["policy"] not in FLOOR.values():
        return row["label"]
    if FLOOR[tasks.get_task(row["task"]).control] == row["policy"]:
        return "random"
    level = next(c for c, floor in FLOOR.items() if floor == row["policy"])
    return f"{row['policy']} ({level})"


def to_markdown(rows: list[dict[str, Any]], command: str) -> str:
    """One line per task: each policy's ``POSC ± ci (POSC/reach; violation steps)``."""
    policies: list[str] = []
    for r in rows:
        label = _column(r)
        if label not in policies:
            policies.append(label)
    head = "| task | " + " | ".join(policies) + " |"
    out = [head, "|" + "---|" * (len(policies) + 1)]
    by_task: dict[str, dict[str, str]] = {}
    for r in rows:
        label = _column(r)
        norm = "-" if r["normalised"] is None else f"{r['normalised']:.3f}"
        cell = f"{r['posc_mean']:.3f} ± {r['posc_ci95']:.3f} ({norm}; {r['violation_steps']:.0f})"
        by_task.setdefault(r["task"], {})[label] = cell
    for tid, cells in by_task.items():
        name = tid.split("/", 1)[1]
        out.append(f"| {name} | " + " | ".join(cells.get(p, "-") for p in policies) + " |")
    n = rows[0]["episodes"]
    out.append("")
    out.append(
        f"Cells: mean POSC ± 95 % interval over {n} seeds (POSC / reach-aware bound; mean "
        f"violation steps). Random = the floor at the task's control level. Command: `{command}`"
    )
    return "\n".join(out) + "\n"


def main(argv: list[str] | None = None) -> list[dict[str, Any]]:
    import contextlib
    import shlex

    from poc_env.agents.benchmarks import write_table_set
    from poc_env.agents.experiments.pool import ray_jobs
    from poc_env.io import check_out

    args = _parse(argv)
    check_out("out", args.out, "folder")  # before the run, not after it
    given = sys.argv[1:] if argv is None else argv
    command = "poc-env bench baselines " + shlex.join(given)
    ctx = ray_jobs(args.ray) if args.ray is not None else contextlib.nullcontext()
    with ctx:
        rows = run(args)
    md = to_markdown(rows, command.strip())
    print(md)
    if args.out:  # both files or neither
        write_table_set(args.out, "baselines", rows, md)
    return rows


if __name__ == "__main__":
    from poc_env.agents.benchmarks import run_main

    run_main(main)
