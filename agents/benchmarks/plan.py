"""Speed (and optionally quality) of the paper-budget plan: adaptive DE on eq. 26.

    python -m poc_env.agents.benchmarks.plan [--scenario paper_6_2] [--uavs 6] [--runs 3]
    [--quality]

One line per figure, on one core (``OMP_NUM_THREADS=1``, ``NUMBA_NUM_THREADS=1``, set before
numpy is imported), medians of ``--runs`` timed runs after a warm-up that keeps JIT compilation
out of the figures:

* ``plan_s``: wall time of one plan, :func:`poc_env.agents.planning.optimizers.adaptive_de` with
the paper's
  budget (NP = 100, G = 300, F0 = 0.2, CR = 0.1, from the scenario's ``planner`` section) on
  ``PlanObjective`` (6 UAVs, the 30 x 40 map of ``paper_6_2``); target
  0.5 s;
* ``evals_per_s``: objective evaluations per second inside that plan (``nfev / plan_s``), and
  ``objective_evals_per_s``: the objective alone, one population call of NP individuals;
* ``scipy_plan_s`` and ``ratio_to_scipy``: :func:`scipy.optimize.differential_evolution` on
  the same objective with the same budget (via :func:`poc_env.agents.planning.optimizers.scipy_de`:
  ``popsize`` individuals, ``maxiter`` generations, vectorised, no polish) and our time over
  its time.

``--quality`` adds the paper's Fig. 22 claim: the final objective of adaptive DE and of classic
DE (constant F = F0) on seeds ``0 .. --seeds - 1`` (default 10), their means, how often
adaptive DE wins, and the adaptive plans' mean POSC against the physical optimum for their
effort (:func:`poc_env.theory.bound.physical_optimum`). It takes a few seconds per seed.

``--planner allocation`` times only the allocation planner
(:mod:`poc_env.agents.planning.allocation`): ``allocation_plan_s`` (target 2 s), its planned POS_C
and POS_C over the reach-aware bound; ``both`` (default) adds those lines after the DE figures.

``--preset tuned`` times and scores the tuned DE constants instead of the paper's (same NP, G;
:func:`poc_env.agents.planning.optimizers.preset_settings`). ``--sweep NP,G,F0,CR ...`` runs
adaptive DE
with each candidate on seeds ``--seed0 .. --seed0 + --seeds - 1`` and prints one table row per
candidate (mean and sd of the final eq. 26 objective, mean POS_C, median plan time): the sweep
behind the ``tuned`` preset (docs/PLANNER.md section 4).

``--scale`` runs issue 24's figures instead (:mod:`poc_env.agents.benchmarks.plan_scale`):
flown ``allocation_plan`` against ``greedy_rectangles`` as shares of the rule-aware bound on
``--episodes`` random priors of ``paper_6_2`` and ``large_400``, planned against flown POS at
2.5, 5 and 10 km cells, and planning time for 24 UAVs on 160 x 160 cells;
``--scale-parts zones --zones N`` times the same two plans with and without ``N`` random no-fly
zones.

``main(argv)`` returns ``{figure: value, ...}``.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "NUMBA_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from poc_env.agents.planning.objective import PlanObjective  # noqa: E402
from poc_env.agents.planning.optimizers import (  # noqa: E402
    adaptive_de,
    classic_de,
    preset_settings,
    scipy_de,
)
from poc_env.config import load_scenario  # noqa: E402
from poc_env.errors import ConfigError  # noqa: E402
from poc_env.helptext import HelpFormatter, examples  # noqa: E402


def build_parser() -> argparse.ArgumentParser:
    """This benchmark's command line (``--help``: options, defaults, examples)."""
    p = argparse.ArgumentParser(
        prog="poc-env bench plan",
        description=__doc__.split("\n")[0],
        formatter_class=HelpFormatter,
        epilog=examples(
            "poc-env bench plan --runs 3",
            "poc-env bench plan --planner de --preset tuned --uavs 4",
            "poc-env bench plan --sweep 100,300,0.2,0.1 60,200,0.15,0.9 --seeds 5",
        ),
    )
    p.add_argument("--scenario", default="paper_6_2", help="built-in name or YAML path")
    p.add_argument("--uavs", type=int, default=6, help="number of UAVs (paper: 6)")
    p.add_argument("--popsize", type=int, default=None, help="NP (default: the scenario's)")
    p.add_argument("--maxiter", type=int, default=None, help="G (default: the scenario's)")
    p.add_argument("--runs", type=int, default=3, help="timed runs per figure (median)")
    p.add_argument("--quality", action="store_true", help="adaptive vs classic DE (slow)")
    p.add_argument("--seeds", type=int, default=10, help="seeds for --quality and --sweep")
    p.add_argument("--preset", default="paper", help="DE settings: paper or tuned")
    p.add_argument(
        "--sweep", nargs="+", default=None, metavar="NP,G,F0,CR", help="adaptive DE candidates"
    )
    p.add_argument("--seed0", type=int, default=0, help="first seed of --sweep")
    p.add_argument(
        "--planner",
        default="both",
        choices=["de", "allocation", "both"],
        help="time adaptive DE, the allocation planner, or both",
    )
    p.add_argument(
        "--scale",
        action="store_true",
        help="issue 24's figures instead: flown allocation_plan vs greedy_rectangles over the "
        "rule-aware bound, planned vs flown across cell sizes, planning time up to 160 x 160 "
        "cells and 24 UAVs (poc_env.agents.benchmarks.plan_scale)",
    )
    p.add_argument("--episodes", type=int, default=10, help="random priors per map (--scale)")
    p.add_argument(
        "--scale-maps", nargs="+", default=None, help="maps of --scale (paper_6_2 large_400)"
    )
    p.add_argument(
        "--scale-parts",
        nargs="+",
        default=None,
        choices=["quality", "cells", "timing", "single", "tight", "zones", "spill"],
        help="parts of --scale to run (default: quality cells timing; single: each airfield's "
        "UAV alone against its own rule-aware bound; tight: the same against the "
        "tour-charged bound too; zones: planning time with and without --zones random no-fly "
        "zones; spill: the spill-charged bound beside the rule-aware one, with quality the "
        "flown POSC over it too)",
    )
    p.add_argument(
        "--zones",
        type=int,
        default=4,
        help="random no-fly zones of --scale-parts zones (inside the search area)",
    )
    p.add_argument(
        "--scale-out",
        default=None,
        help="--scale: also write every episode's figures (per map, seed and policy) to this "
        "JSON file",
    )
    return p


def allocation(sc, uavs: int, runs: int) -> dict[str, float]:
    """``allocation_plan_s`` (median of ``runs`` timed plans after a warm-up), its planned POS_C
    and POS_C over the reach-aware bound
    (:func:`poc_env.agents.planning.allocation.make_allocation_plan` on the scenario's prior)."""
    from poc_env.agents.planning.allocation import make_allocation_plan

    make_allocation_plan(sc, uavs=uavs)  # warm-up
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        plan = make_allocation_plan(sc, uavs=uavs)
        times.append(time.perf_counter() - t0)
    out = {
        "allocation_plan_s": statistics.median(times),
        "allocation_posc": float(plan["posc"]),
        "allocation_posc_over_reach": float(plan["posc"] / plan["bound_reach"]),
    }
    _line("allocation_plan_s", out["allocation_plan_s"], "allocation planner (target <= 2 s)")
    _line("allocation_posc", out["allocation_posc"], "planned POS_C (whole flight path swept)")
    _line(
        "allocation_posc_over_reach",
        out["allocation_posc_over_reach"],
        f"planned POS_C / reach-aware bound {plan['bound_reach']:.4f}",
    )
    return out


def _candidate(text: str) -> tuple[int, int, float, float]:
    try:
        a, b, c, d = text.split(",")
        return int(a), int(b), float(c), float(d)
    except ValueError:
        raise ConfigError("sweep", text, "NP,G,F0,CR (e.g. 100,300,0.15,0.9)") from None


def sweep(obj: PlanObjective, candidates: list[str], seeds: range) -> dict[str, float]:
    """One row per candidate ``NP,G,F0,CR``: eq. 26 mean and sd, POS_C mean, median time."""
    cands = [_candidate(c) for c in candidates]
    print("| NP | G | F0 | CR | eq. 26 mean | sd | POS_C mean | plan_s (median) |", flush=True)
    print("| --- | --- | --- | --- | --- | --- | --- | --- |", flush=True)
    out: dict[str, float] = {}
    for npop, gens, f0, cr in cands:
        fs, ts, ps = [], [], []
        for s in seeds:
            t0 = time.perf_counter()
            r = adaptive_de(obj, obj.bounds, popsize=npop, maxiter=gens, f0=f0, cr=cr, rng=s)
            ts.append(time.perf_counter() - t0)
            fs.append(r.fun)
            ps.append(float(obj.evaluate(r.x[None]).posc[0]))
        key = f"{npop},{gens},{f0:g},{cr:g}"
        out[key] = float(np.mean(fs))
        print(
            f"| {npop} | {gens} | {f0:g} | {cr:g} | {np.mean(fs):.4f} | {np.std(fs):.4f} "
            f"| {np.mean(ps):.4f} | {statistics.median(ts):.2f} |",
            flush=True,
        )
    return out


def _line(name: str, value: float, note: str = "") -> None:
    print(f"{name:26s} {value:12.4g}  {note}".rstrip(), flush=True)


def main(argv: list[str] | None = None) -> dict[str, float]:
    from poc_env.agents.benchmarks import check_counts
    from poc_env.io import check_out

    args = build_parser().parse_args(argv)
    check_counts(args, uavs=1, runs=1, seeds=1, episodes=1, seed0=0, zones=0)
    check_out("scale_out", args.scale_out, "file")  # before the run, not after it
    if args.scale:
        from poc_env.agents.benchmarks import plan_scale

        maps = args.scale_maps or plan_scale.MAPS
        return plan_scale.main(
            maps,
            args.episodes,
            args.seed0,
            args.runs,
            args.scale_parts,
            args.scale_out,
            zones=args.zones,
        )
    sc = load_scenario(args.scenario)
    obj = PlanObjective(sc, uavs=args.uavs)
    if args.sweep:
        adaptive_de(obj, obj.bounds, popsize=8, maxiter=2, rng=0)  # warm-up (JIT)
        return sweep(obj, args.sweep, range(args.seed0, args.seed0 + args.seeds))
    if args.planner == "allocation":
        print(f"# {sc.name}: {obj.n} UAVs; one core; medians of {args.runs} runs", flush=True)
        return allocation(sc, obj.n, args.runs)
    preset = preset_settings(args.preset, sc.planner)
    npop = args.popsize or preset["popsize"]
    gens = args.maxiter or preset["maxiter"]
    f0, cr = preset["f0"], preset["cr"]
    budget: dict[str, Any] = dict(popsize=npop, maxiter=gens)
    print(
        f"# {sc.name}: {obj.n} UAVs, {obj.grid.ny} x {obj.grid.nx} cells, NP {npop}, G {gens}, "
        f"F0 {f0}, CR {cr} (preset {args.preset}); one core; medians of {args.runs} runs",
        flush=True,
    )
    # warm-up: compile (or load) the kernels
    adaptive_de(obj, obj.bounds, popsize=npop, maxiter=2, rng=0)
    scipy_de(obj, obj.bounds, popsize=npop, maxiter=2, rng=0)

    out: dict[str, float] = {}
    times, nfev = [], 0
    for k in range(args.runs):
        t0 = time.perf_counter()
        res = adaptive_de(obj, obj.bounds, f0=f0, cr=cr, rng=k, **budget)
        times.append(time.perf_counter() - t0)
        nfev = res.nfev
    out["plan_s"] = statistics.median(times)
    _line("plan_s", out["plan_s"], f"adaptive_de, {nfev} evaluations (target <= 0.5 s)")
    out["evals_per_s"] = nfev / out["plan_s"]
    _line("evals_per_s", out["evals_per_s"], "inside the plan (DE overhead included)")

    rng = np.random.default_rng(0)
    lo, hi = obj.bounds.T
    pops = [lo + rng.random((npop, obj.dim)) * (hi - lo), res.population]
    call_times = []
    for _ in range(max(args.runs, 5)):
        for pop in pops:
            t0 = time.perf_counter()
            obj(pop)
            call_times.append(time.perf_counter() - t0)
    out["objective_evals_per_s"] = npop / statistics.median(call_times)
    _line(
        "objective_evals_per_s",
        out["objective_evals_per_s"],
        "one population call (random and converged populations)",
    )

    s_times = []
    for k in range(args.runs):
        t0 = time.perf_counter()
        scipy_de(obj, obj.bounds, rng=k, **budget)
        s_times.append(time.perf_counter() - t0)
    out["scipy_plan_s"] = statistics.median(s_times)
    _line("scipy_plan_s", out["scipy_plan_s"], "scipy.optimize.differential_evolution, same budget")
    out["ratio_to_scipy"] = out["plan_s"] / out["scipy_plan_s"]
    _line("ratio_to_scipy", out["ratio_to_scipy"], "plan_s / scipy_plan_s (< 1: faster)")
    if args.planner == "both":
        out.update(allocation(sc, obj.n, args.runs))

    if args.quality:
        ada, cla, posc, bound = [], [], [], []
        for seed in range(args.seeds):
            a = adaptive_de(obj, obj.bounds, f0=f0, cr=cr, rng=seed, **budget)
            c = classic_de(obj, obj.bounds, f0=f0, cr=cr, rng=seed, **budget)
            ada.append(a.fun)
            cla.append(c.fun)
            posc.append(float(obj.evaluate(a.x[None]).posc[0]))
            bound.append(obj.upper_bound(a.x))
        out["adaptive_de_mean_f"] = float(np.mean(ada))
        out["classic_de_mean_f"] = float(np.mean(cla))
        out["adaptive_wins"] = float(np.sum(np.array(ada) < np.array(cla)))
        out["adaptive_posc_mean"] = float(np.mean(posc))
        out["adaptive_posc_over_bound"] = float(np.mean(np.array(posc) / np.array(bound)))
        n = args.seeds
        _line("adaptive_de_mean_f", out["adaptive_de_mean_f"], f"eq. 26, mean of {n} seeds")
        _line("classic_de_mean_f", out["classic_de_mean_f"], f"eq. 26, mean of {n} seeds")
        _line("adaptive_wins", out["adaptive_wins"], f"of {n} seeds (lower eq. 26 than classic)")
        _line("adaptive_posc_mean", out["adaptive_posc_mean"], "POSC of the adaptive plans")
        _line(
            "adaptive_posc_over_bound",
            out["adaptive_posc_over_bound"],
            "POSC / physical optimum for the plan's effort (objective's model)",
        )
    return out


if __name__ == "__main__":
    from poc_env.agents.benchmarks import run_main

    run_main(main)
