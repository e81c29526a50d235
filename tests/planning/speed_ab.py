"""Issue 24, session i24-speed (docs/PLANNER.md, "Faster planning on priors of many small
blobs"): a script, not a test.

``digest OUT.json [thorough]``
    The digest (:func:`effort_ab._digest`: sha256 of every UAV's waypoints and the planned POS)
    of the default allocation plan of ``poc-env bench plan --scale``'s timing case
    ``large_400_160x160_24uav_300blobs`` (:func:`blobs_case`), and with ``thorough`` also of
    the ``thorough`` plans of ``paper_6_2``'s random priors 0-2: run in two trees and compare
    (a speed-up must leave them equal).
``time CASE RUNS``
    ``RUNS`` default plans of a timing case (``paper_6_2``, ``large_400_160x160_24uav``,
    ``large_400_160x160_24uav_300blobs``; ``paper_6_2_thorough_SEED``: the ``thorough`` plan
    of ``paper_6_2``'s random prior ``SEED``; ``paper_6_2_standard_SEED`` its ``standard``
    plan) after a warm-up plan (``refine=0``: JIT, caches), each plan's wall and CPU time
    printed (one process: run it under another tree for a pair).
``pair BASE CASE ROUNDS OUT.json``
    ``ROUNDS`` rounds of ``time CASE 1``, one process per tree and round, alternating this
    tree and the tree ``BASE`` (a checkout of the base commit, e.g. ``git archive 50dfd7a |
    tar -x -C BASE``; run with ``PYTHONPATH=BASE``, this tree first), one thread each: per
    round both trees' wall and CPU time of the plan and the load; the records and the paired
    ratios' medians written to ``OUT.json`` after every round.
``parts CASE RUNS``
    As ``time``, with the CPU time of the plan's steps (the allocation planner's module
    names wrapped: the refinement, the box start, the allocation start's lines and their
    assignment, the sampled scores, ...), one JSON line per plan.
``profile CASE OUT.prof``
    One default plan of a case under cProfile (after the warm-up), the stats written to
    ``OUT.prof`` and the top 30 by cumulative and by own time printed.

Run from the repository root, one thread: ``OMP_NUM_THREADS=1 python tests/planning/speed_ab.py
digest out.json thorough``.
"""

from __future__ import annotations

import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from effort_ab import _digest

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.config import load_scenario


def blobs_case():
    """The timing case of many small blobs (:func:`poc_env.agents.benchmarks.plan_scale.
    timing`): (scenario, UAVs, prior)."""
    from poc_env.theory.probability_map import Grid, random_gaussian_mixture

    big = load_scenario("large_400", {"map.cell_km": 2.5})
    blobs = random_gaussian_mixture(
        Grid.from_config(big.map), np.random.default_rng(0), (300, 300), (0.003, 0.008), (0, 0)
    )
    return big, 24, blobs


def case(name: str):
    """(scenario, UAVs, prior) of a timing case."""
    if name == "paper_6_2":
        return load_scenario("paper_6_2"), None, None
    if name == "large_400_160x160_24uav":
        return load_scenario("large_400", {"map.cell_km": 2.5}), 24, None
    if name == "large_400_160x160_24uav_300blobs":
        return blobs_case()
    if name.startswith(("paper_6_2_thorough_", "paper_6_2_standard_")):  # options(name)
        sc = load_scenario("paper_6_2")
        return sc, None, episode_prior(sc, int(name.rsplit("_", 1)[1]))
    raise SystemExit(f"unknown case {name}")


def options(name: str):
    """The plan options of a case: ``thorough`` for ``paper_6_2_thorough_SEED``, ``standard``
    for ``paper_6_2_standard_SEED`` (i24-cheapolish), else the defaults (None)."""
    from poc_env.agents.planning.options import PlanOptions

    for effort in ("thorough", "standard"):
        if f"_{effort}_" in name:
            return PlanOptions.preset(effort)
    return None


def digest(out: str, thorough: bool) -> None:
    from poc_env.agents.planning.allocation import make_allocation_plan
    from poc_env.agents.planning.options import PlanOptions

    recs = {}
    sc, uavs, prior = blobs_case()
    t0 = time.perf_counter()
    p = make_allocation_plan(sc, prior=prior, uavs=uavs)
    recs["large_400_160x160_24uav_300blobs"] = {
        "digest": _digest(p), "posc": float(p["posc"]), "start": p["start"],
        "plan_s": time.perf_counter() - t0,
    }  # fmt: skip
    print(recs, flush=True)
    if thorough:
        sc = load_scenario("paper_6_2")
        for seed in (0, 1, 2):
            t0 = time.perf_counter()
            p = make_allocation_plan(
                sc, prior=episode_prior(sc, seed), options=PlanOptions.preset("thorough")
            )
            key = f"paper_6_2:{seed}:thorough"
            recs[key] = {"digest": _digest(p), "posc": float(p["posc"]), "start": p["start"],
                         "plan_s": time.perf_counter() - t0}  # fmt: skip
            print(key, recs[key], flush=True)
    with open(out + ".tmp", "w") as f:
        json.dump(recs, f, indent=1)
    os.replace(out + ".tmp", out)


def timing(name: str, runs: int) -> None:
    from poc_env.agents.planning.allocation import make_allocation_plan

    sc, uavs, prior = case(name)
    make_allocation_plan(sc, prior=prior, uavs=uavs, refine=0)  # warm-up (JIT)
    for _ in range(runs):
        w0, c0 = time.perf_counter(), time.process_time()
        p = make_allocation_plan(sc, prior=prior, uavs=uavs, options=options(name))
        print(json.dumps({"case": name, "wall_s": time.perf_counter() - w0,
                          "cpu_s": time.process_time() - c0, "load": os.getloadavg()[0],
                          "digest": _digest(p)[:12]}), flush=True)  # fmt: skip


def pair(base: str, name: str, rounds: int, out: str) -> None:
    import statistics
    import subprocess

    here = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    script = os.path.join("tests", "planning", "speed_ab.py")
    recs: list[dict] = []
    for r in range(rounds):
        for tree in ("this", "base"):
            env = {**os.environ, "OMP_NUM_THREADS": "1"}
            cwd = here
            if tree == "base":
                env["PYTHONPATH"] = base
                cwd = base
            cmd = [sys.executable, os.path.join(here, script), "time", name, "1"]
            res = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, check=True)
            rec = json.loads(res.stdout.strip().splitlines()[-1])
            recs.append({"round": r, "tree": tree, **rec})
            print(recs[-1], flush=True)
        this = [x for x in recs if x["tree"] == "this"]
        other = [x for x in recs if x["tree"] == "base"]
        summary = {
            key: {
                "this_median": statistics.median(x[key] for x in this),
                "base_median": statistics.median(x[key] for x in other),
                "ratio_median": statistics.median(a[key] / b[key] for a, b in zip(this, other)),
            }
            for key in ("wall_s", "cpu_s")
        }
        loads = [x["load"] for x in recs]
        summary["load"] = {"min": min(loads), "max": max(loads)}
        with open(out + ".tmp", "w") as f:
            json.dump({"case": name, "records": recs, "summary": summary}, f, indent=1)
        os.replace(out + ".tmp", out)
    print(json.dumps(summary), flush=True)


#: the steps :func:`parts` times (names in :mod:`poc_env.agents.planning.allocation`).
STEPS = ("refine_routes", "box_routes", "layered_tracks", "_assign", "reach_optimum",
         "sampled_sweep", "_cell_pos", "fit_lawnmowers", "_swept_areas", "plan_geography",
         "_fan_out", "_trim", "make_greedy_rectangles_plan")  # fmt: skip


def parts(name: str, runs: int) -> None:
    import collections

    import poc_env.agents.planning.allocation as alloc
    import poc_env.agents.planning.greedy_rectangles as greedy

    acc: dict[str, float] = collections.defaultdict(float)

    def wrap(mod, step: str) -> None:
        f = getattr(mod, step)

        def timed(*a, **k):
            c0 = time.process_time()
            try:
                return f(*a, **k)
            finally:
                acc[step] += time.process_time() - c0

        setattr(mod, step, timed)

    for step in STEPS:
        wrap(greedy if step == "make_greedy_rectangles_plan" else alloc, step)
    sc, uavs, prior = case(name)
    alloc.make_allocation_plan(sc, prior=prior, uavs=uavs, refine=1)  # warm-up (JIT)
    for _ in range(runs):
        acc.clear()
        w0, c0 = time.perf_counter(), time.process_time()
        alloc.make_allocation_plan(sc, prior=prior, uavs=uavs)
        rec = {"case": name, "wall_s": round(time.perf_counter() - w0, 3),
               "cpu_s": round(time.process_time() - c0, 3), "load": os.getloadavg()[0]}  # fmt: skip
        rec.update({k: round(v, 3) for k, v in sorted(acc.items(), key=lambda t: -t[1])})
        print(json.dumps(rec), flush=True)


def profile(name: str, out: str) -> None:
    import cProfile
    import pstats

    from poc_env.agents.planning.allocation import make_allocation_plan

    sc, uavs, prior = case(name)
    make_allocation_plan(sc, prior=prior, uavs=uavs, refine=0)  # warm-up (JIT)
    pr = cProfile.Profile()
    pr.enable()
    make_allocation_plan(sc, prior=prior, uavs=uavs)
    pr.disable()
    pr.dump_stats(out)
    st = pstats.Stats(out)
    st.sort_stats("cumulative").print_stats(40)
    st.sort_stats("tottime").print_stats(30)


if __name__ == "__main__":
    cmd, *args = sys.argv[1:]
    if cmd == "digest":
        digest(args[0], len(args) > 1 and args[1] == "thorough")
    elif cmd == "time":
        timing(args[0], int(args[1]))
    elif cmd == "pair":
        pair(args[0], args[1], int(args[2]), args[3])
    elif cmd == "parts":
        parts(args[0], int(args[1]))
    elif cmd == "profile":
        profile(args[0], args[1])
    else:
        raise SystemExit(__doc__)
