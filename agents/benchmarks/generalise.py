"""Generalisation: how much of its score a policy keeps on conditions it was not tuned for.

    poc-env bench generalise [--scenario paper_6_2] [--policies P,...] [--conditions C,...]
                             [--episodes 50] [--seed 1000] [--workers K] [--out DIR] [--quiet]

Every condition is the scenario (``--scenario``, default ``paper_6_2``) with a few overrides
(:func:`poc_env.config.load_scenario`, dotted keys as ``--overrides``). Every policy flies the
same seeds ``--seed .. --seed + episodes - 1`` on every condition, each seed with its own
random Gaussian-mixture prior from the held-out evaluation stream
(:func:`poc_env.agents.experiments.evaluate.episode_prior`, ``EVAL_PRIOR_STREAM``: a generator
training never draws from), drawn on the condition's own grid. The conditions, with their exact
overrides (written for ``paper_6_2``: 200 km wide x 150 km tall, 40 x 30 cells of 5 km,
airfields at (20, -60) and (120, -60) km, six UAVs, one shared belief):

- ``train`` (no overrides): the task's own geometry; only the priors are new (the evaluation
  stream). The reference of ``kept``; it is always flown, listed or not.
- ``tall_150x200`` (``map.width_km=150 map.height_km=200``): the area turned on its side,
  30 columns x 40 rows, same airfields: the far edge is now 260 km north of the airfields
  instead of 210 km. Tests whether a policy learned the map's layout rather than to follow
  the belief.
- ``cells_6km`` (``map.cell_km=6 map.width_km=198``): coarser cells, 33 x 25 of 6 km. The
  width becomes 198 km because ``width_km`` and ``height_km`` must be whole multiples of
  ``cell_km`` (:class:`poc_env.config.MapConfig`; 200 km is not, 150 km is). Tests a
  different raster resolution over (almost) the same area.
- ``comms_belief`` (``comms.belief_sharing=comms``): each UAV keeps the survival of its own
  sweeps and copies another's only while the active topology links them, possibly through
  relays (:func:`poc_env.sim.core.share_beliefs`), instead of one shared belief (the paper's
  and the training setting). Tests decisions on stale, local beliefs -- when links break:
  with ``paper_6_2``'s 150 km range the six UAVs stay linked almost throughout (on seed 1000
  the PPO checkpoint's swarm was split for 2 of 152 steps and every UAV's belief equalled the
  global one), so this condition mostly checks that the comms path changes nothing there.
- ``comms_60km`` (``comms.belief_sharing=comms comms.range_km=60``): the same with a 60 km
  radio range, so the swarm does split (62 of 152 steps on seed 1000 with the PPO checkpoint)
  and beliefs differ; eq. 24's two-neighbour rule is broken more often, which the violation
  column shows. ``allocation_plan`` and ``de_plan`` plan once from the belief at take-off and
  ``lawnmower`` ignores it, so only belief-driven policies (``greedy_bayes``, learned ones)
  can lose from stale beliefs here.

A learned policy can fly every condition because the compass observation
(:mod:`poc_env.agents.rl.pilot`, :class:`poc_env.sim.observations.CompassFeatures`) is size-free:
shares
of the remaining POC by sector and distance ring around the UAV, and the UAV's own state, in a
fixed-length vector whatever the grid's shape or cell size. So one checkpoint
(``ppo:ppo_heading_paper_6_2``, shipped in ``agents/checkpoints``) flies every geometry without
retraining; a checkpoint of a raster recipe (``shared``, ``central``) is tied to its grid and
stops with a ``checkpoint`` error on the other shapes.

Per condition and policy: mean POSC with its 95 % interval over the seeds (Student's t,
:func:`poc_env.stats.ci95`), the mean reach-aware bound of the condition's priors
(:func:`poc_env.theory.bound.reach_bound`: the best POSC any swarm could reach with transit
from its airfields at top speed), the normalised score (mean over episodes of POSC / the
episode's reach-aware bound: a bigger or finer map changes the attainable POSC, the ratio
compares like with like), the mean constraint-violation steps, and

    kept = normalised(condition) / normalised(train)

the share of its ``train`` normalised score the policy keeps (1 on ``train``; empty when the
``train`` score is 0).

Writes ``generalise.csv`` (one row per condition and policy) and ``generalise.md`` (the table
printed on stdout) into ``--out``, both or neither (:func:`poc_env.io.atomic_dir`).
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any

from poc_env.errors import ConfigError
from poc_env.helptext import HelpFormatter, examples

#: condition name -> dotted-key overrides of the scenario (see the module docstring).
CONDITIONS: dict[str, dict[str, Any]] = {
    "train": {},
    "tall_150x200": {"map.width_km": 150, "map.height_km": 200},
    "cells_6km": {"map.cell_km": 6, "map.width_km": 198},
    "comms_belief": {"comms.belief_sharing": "comms"},
    "comms_60km": {"comms.belief_sharing": "comms", "comms.range_km": 60},
}
#: the condition ``kept`` divides by.
REFERENCE = "train"
DEFAULT_POLICIES = (
    "allocation_plan",
    "greedy_bayes",
    "de_plan",
    "lawnmower",
    "ppo:ppo_heading_paper_6_2",
)
#: first episode seed: the default ``seed0`` of
# :func:`poc_env.agents.experiments.evaluate.evaluate`.
SEED0 = 1000


def build_parser() -> argparse.ArgumentParser:
    """This benchmark's command line (``--help``: options, defaults, examples)."""
    p = argparse.ArgumentParser(
        formatter_class=HelpFormatter,
        epilog=examples(
            "poc-env bench generalise --episodes 5 --policies greedy_bayes,allocation_plan"
        ),
        prog="poc-env bench generalise",
        description=(__doc__ or "").split("\n")[0],
    )
    p.add_argument("--scenario", default="paper_6_2", help="scenario the conditions change")
    p.add_argument(
        "--policies",
        default=",".join(DEFAULT_POLICIES),
        help="comma-separated registered policies (ppo:NAME for a shipped checkpoint)",
    )
    p.add_argument(
        "--conditions",
        default=",".join(CONDITIONS),
        help="comma-separated, of: " + ", ".join(CONDITIONS) + " (train is always flown)",
    )
    p.add_argument("--episodes", type=int, default=50)
    p.add_argument("--seed", type=int, default=SEED0, help="first episode seed")
    p.add_argument("--workers", type=int, default=1)
    p.add_argument("--out", default=None, help="folder for generalise.csv and generalise.md")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    return p


def _parse(argv: list[str] | None) -> argparse.Namespace:
    return build_parser().parse_args(argv)


def _names(field: str, text: str) -> list[str]:
    """A comma list without blanks or repeats (order kept); empty -> ConfigError."""
    names = list(dict.fromkeys(s.strip() for s in str(text).split(",") if s.strip()))
    if not names:
        raise ConfigError(field, text, "a non-empty comma-separated list")
    return names


def conditions(names: list[str]) -> list[str]:
    """The conditions to fly, ``train`` first (the reference of ``kept``).

    Raises
    ------
    ConfigError
        Field ``conditions`` for a name not in :data:`CONDITIONS` (listing them).
    """
    for n in names:
        if n not in CONDITIONS:
            allowed = "a comma-separated list of: " + ", ".join(CONDITIONS)
            raise ConfigError("conditions", n, allowed)
    return [REFERENCE, *(n for n in names if n != REFERENCE)]


def condition_scenario(scenario: Any, condition: str) -> Any:
    """The :class:`~poc_env.config.Scenario` of ``condition``: ``scenario`` with its
    overrides (:data:`CONDITIONS`), validated as a YAML file would be."""
    from poc_env.config import load_scenario

    if condition not in CONDITIONS:
        raise ConfigError("conditions", condition, "one of: " + ", ".join(CONDITIONS))
    return load_scenario(scenario, CONDITIONS[condition])


def run(args: argparse.Namespace) -> list[dict[str, Any]]:
    """Rows (condition, policy, episodes, posc_mean, posc_ci95, bound_reach, normalised,
    violation_steps, kept), conditions in order, policies in order within each.

    Every name, every condition's scenario and every policy is checked before the first
    episode runs.
    """
    from poc_env.agents.experiments.evaluate import check_policies, evaluate

    conds = conditions(_names("conditions", args.conditions))
    policies = _names("policies", args.policies)
    check_policies(policies)
    scenarios = {c: condition_scenario(args.scenario, c) for c in conds}
    rows: list[dict[str, Any]] = []
    for c in conds:
        t0 = time.perf_counter()
        ev = evaluate(
            scenarios[c],
            policies,
            episodes=args.episodes,
            seed0=args.seed,
            workers=args.workers,
            random_priors=True,
        )
        for r in ev.rows():
            rows.append(
                {
                    "condition": c,
                    "policy": r["policy"],
                    "episodes": r["episodes"],
                    "posc_mean": r["posc_mean"],
                    "posc_ci95": r["posc_ci95"],
                    "bound_reach": r["bound_reach"],
                    "normalised": r["normalised"],
                    "violation_steps": r["violation_steps"],
                }
            )
        if not args.quiet:
            wall = time.perf_counter() - t0
            print(f"{c}: done ({wall:.0f} s)", file=sys.stderr, flush=True)
    ref = {r["policy"]: r["normalised"] for r in rows if r["condition"] == REFERENCE}
    for r in rows:
        base, mine = ref[r["policy"]], r["normalised"]
        r["kept"] = None if not base or mine is None else mine / base
    return rows


def _f(v: Any, fmt: str) -> str:
    return "-" if v is None else format(v, fmt)


def to_markdown(rows: list[dict[str, Any]], command: str) -> str:
    """The long table (one line per condition and policy), then ``kept`` per policy (rows) and
    condition (columns)."""
    out = [
        "| condition | policy | POSC ± 95 % | reach bound | POSC/reach | kept | violation steps |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        out.append(
            f"| {r['condition']} | {r['policy']} | {r['posc_mean']:.4f} ± {r['posc_ci95']:.4f} | "
            f"{_f(r['bound_reach'], '.4f')} | {_f(r['normalised'], '.4f')} | "
            f"{_f(r['kept'], '.3f')} | {r['violation_steps']:.1f} |"
        )
    conds = list(dict.fromkeys(r["condition"] for r in rows))
    policies = list(dict.fromkeys(r["policy"] for r in rows))
    kept = {(r["condition"], r["policy"]): r["kept"] for r in rows}
    out += ["", "| kept | " + " | ".join(conds) + " |", "|---|" + "---|" * len(conds)]
    for p in policies:
        out.append(f"| {p} | " + " | ".join(_f(kept[(c, p)], ".3f") for c in conds) + " |")
    overrides = "; ".join(
        f"{c}: " + (" ".join(f"{k}={v}" for k, v in CONDITIONS[c].items()) or "none") for c in conds
    )
    out += [
        "",
        f"Mean over {rows[0]['episodes']} seeds, each with its own held-out random prior on the "
        "condition's grid (same seeds for every policy and condition). POSC/reach = mean of "
        "per-episode POSC / reach-aware bound; kept = POSC/reach on the condition / on train. "
        f"Overrides: {overrides}. Command: `{command}`",
    ]
    return "\n".join(out) + "\n"


def main(argv: list[str] | None = None) -> list[dict[str, Any]]:
    import shlex

    from poc_env.agents.benchmarks import write_table_set
    from poc_env.io import check_out

    args = _parse(argv)
    check_out("out", args.out, "folder")  # before the run, not after it
    given = sys.argv[1:] if argv is None else argv
    command = "poc-env bench generalise " + shlex.join(given)
    rows = run(args)
    md = to_markdown(rows, command.strip())
    print(md)
    if args.out:  # both files or neither
        write_table_set(args.out, "generalise", rows, md)
    return rows


if __name__ == "__main__":
    from poc_env.agents.benchmarks import run_main

    run_main(main)
