"""Issue 24's router figures (docs/PLANNER.md "Planning time with no-fly zones"): a script,
not a test.

``digest OUT.json``
    Plans :data:`CASES` (random no-fly zones of ``poc-env bench plan --scale --scale-parts
    zones``, :func:`~poc_env.agents.benchmarks.plan_scale.random_zones`) with the allocation
    planner, the greedy rectangles and the DE planner, and writes a SHA-256 of every plan's
    waypoints (bytes of the float64 arrays) and its planned POS. Run it with two trees'
    ``PYTHONPATH`` on the same machine and compare the files: equal digests are plans equal bit
    for bit (digests are machine-bound: another CPU may round differently).
``timing TREE_A TREE_B N [CASE ...]``
    Allocation planning time with 4 zones of each case (default ``paper_6_2`` and
    ``large_400_160x160_24uav``, :data:`poc_env.agents.benchmarks.plan_scale.ZONE_CASES`; the
    zones of ``poc-env bench plan --scale --scale-parts zones --zones 4``), the
    two trees alternated ``N`` times, one subprocess per tree and round (one thread, two plans
    each after a warm-up plan, the faster kept); medians and pair ratios B / A of the wall
    time and of the process's CPU time (``time.process_time``: on a shared, loaded machine
    the steadier of the two), with the load.

``profile [CASE]``
    cProfile of one allocation plan of ``CASE`` (default ``paper_6_2``) with the bench's 4
    zones, after a warm-up plan: the 25 costliest functions by cumulative time, then the
    router's share (:meth:`~poc_env.sim.routing.ZoneRouter.reroute` over the whole plan).

``breakdown [CASE] [N]``
    Where the zones' extra planning time goes: ``N`` (default 3) allocation plans of ``CASE``
    (default ``paper_6_2``) with the bench's 4 zones and without zones, alternated after a
    warm-up plan of each, in one process: the process's CPU time of the plan, of the
    refinement runs (:func:`~poc_env.agents.planning.refine.refine_routes`, how many) and of
    the router (every :class:`~poc_env.sim.routing.ZoneRouter` call from outside the router:
    its construction, ``reach_share``, ``reroute``); medians.

``router TREE_A [CASE] [N]``
    The router alone, ``TREE_A``'s ``poc_env/sim/routing.py`` against this one's in one
    process: every ``reroute`` call of one allocation plan of ``CASE`` (default
    ``paper_6_2``) with the bench's 4 zones is recorded, then replayed ``N`` times (default
    9) through fresh routers of each (as a plan builds them), alternated; CPU time medians
    and pair ratios, and a check that both answer every call as the plan did.

``plan-router TREE_A [CASE] [N]``
    Whole allocation plans of ``CASE`` (default ``paper_6_2``) with the bench's 4 zones, in
    one process, with ``TREE_A``'s ``ZoneRouter`` and with this one's patched into the
    planners (the allocation planner and the greedy rectangles), alternated ``N`` times
    (default 8) after a plan of each: both plans' waypoint digests, CPU time medians and pair
    ratios (the plan's time change that the router alone makes).

Run from the repository root: ``OMP_NUM_THREADS=1 python tests/planning/zones_ab.py timing
/work/main . 3``.
"""

from __future__ import annotations

import hashlib
import json
import os
import statistics
import subprocess
import sys
import time
from typing import Any

import numpy as np

#: label -> (scenario, overrides, UAVs or None, zones, zone seed)
CASES: dict[str, tuple[str, dict, int | None, int, int]] = {
    "paper_6_2_z4_s0": ("paper_6_2", {}, None, 4, 0),
    "paper_6_2_z2_s1": ("paper_6_2", {}, None, 2, 1),
    "paper_6_2_z3_s2": ("paper_6_2", {}, None, 3, 2),
    "paper_6_2_z6_s3": ("paper_6_2", {}, None, 6, 3),
    "paper_6_2_z8_s4": ("paper_6_2", {}, None, 8, 4),
    "paper_6_2_z4_s5_3uav": ("paper_6_2", {}, 3, 4, 5),
    "large_400_z4_s0": ("large_400", {}, None, 4, 0),
    "large_400_z6_s6": ("large_400", {}, None, 6, 6),
}


def zoned(name: str, over: dict, n_zones: int, seed: int | np.random.Generator):
    """``name`` with ``n_zones`` random zones drawn from ``default_rng(seed)`` (or ``seed``
    itself, a generator)."""
    from poc_env.agents.benchmarks.plan_scale import random_zones
    from poc_env.config import load_scenario

    m = load_scenario(name, over).map
    ox, oy = (v / 1000 for v in m.origin_m)
    drawn = random_zones(m.width_m / 1000, m.height_m / 1000, n_zones, np.random.default_rng(seed))
    zones = [[[x + ox, y + oy] for x, y in z] for z in drawn]
    names = [f"Z-{i + 1}" for i in range(n_zones)]
    return load_scenario(name, {**over, "map.no_fly_zones_km": zones, "map.no_fly_names": names})


def _digest(plan: dict[str, Any]) -> str:
    h = hashlib.sha256()
    for u in plan["uavs"]:
        h.update(np.asarray(u["waypoints_m"], dtype=float).tobytes())
        h.update(b"|")
    return h.hexdigest()[:16]


def digest(out: str) -> None:
    from poc_env.agents.planning.allocation import make_allocation_plan
    from poc_env.agents.planning.greedy_rectangles import make_greedy_rectangles_plan
    from poc_env.agents.planning.planner import make_plan

    recs = {}
    for label, (name, over, uavs, nz, seed) in CASES.items():
        sc = zoned(name, over, nz, seed)
        t0 = time.perf_counter()
        plan = make_allocation_plan(sc, uavs=uavs)
        recs[f"{label} allocation"] = [_digest(plan), float(plan["posc"])]
        plan = make_greedy_rectangles_plan(sc, uavs=uavs)
        recs[f"{label} greedy"] = [_digest(plan), float(plan["posc"])]
        if name == "paper_6_2":
            plan = make_plan(sc, planner="de", uavs=uavs, seed=seed, maxiter=5, popsize=8)
            recs[f"{label} de"] = [_digest(plan), float(plan["posc"])]
        print(label, recs[f"{label} allocation"], round(time.perf_counter() - t0, 2), flush=True)
    with open(out, "w") as f:
        json.dump(recs, f, indent=1)


def one(case: str) -> None:
    """Child: warm-up plan, then two timed plans of ``case`` with 4 zones; prints JSON."""
    from poc_env.agents.planning.allocation import make_allocation_plan

    sc, uavs = _bench_case(case)
    make_allocation_plan(sc, uavs=uavs)
    ts, cpu = [], []
    for _ in range(2):
        t0, c0 = time.perf_counter(), time.process_time()
        plan = make_allocation_plan(sc, uavs=uavs)
        ts.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    print(json.dumps({"s": min(ts), "cpu": min(cpu), "posc": float(plan["posc"]),
                      "digest": _digest(plan)}))  # fmt: skip


def _bench_case(case: str):
    """``case``'s scenario with the bench's 4 zones (drawn case after case from one rng)."""
    from poc_env.agents.benchmarks.plan_scale import ZONE_CASES

    rng = np.random.default_rng(0)
    for label, (name, over, _) in ZONE_CASES.items():
        sc = zoned(name, over, 4, rng)
        if label == case:
            return sc, ZONE_CASES[case][2]
    raise KeyError(case)


def profile(case: str) -> None:
    import cProfile
    import pstats

    from poc_env.agents.planning.allocation import make_allocation_plan

    sc, uavs = _bench_case(case)
    make_allocation_plan(sc, uavs=uavs)
    prof = cProfile.Profile()
    prof.enable()
    make_allocation_plan(sc, uavs=uavs)
    prof.disable()
    st = pstats.Stats(prof)
    st.sort_stats("cumulative").print_stats(25)
    total = max(v[3] for v in st.stats.values())  # type: ignore[attr-defined]
    router = sum(v[3] for k, v in st.stats.items()  # type: ignore[attr-defined]
                 if k[0].endswith("routing.py") and k[2] == "reroute")  # fmt: skip
    print(f"router (reroute) {router:.3f} s of {total:.3f} s: {router / total:.1%}", flush=True)


def breakdown(case: str, n: int) -> None:
    import functools

    import poc_env.agents.planning.allocation as alloc
    import poc_env.sim.routing as routing
    from poc_env.agents.benchmarks.plan_scale import ZONE_CASES
    from poc_env.config import load_scenario

    spent = {"refine": 0.0, "router": 0.0, "runs": 0}
    depth = [0]

    def timed(f, what):
        @functools.wraps(f)
        def g(*a, **k):
            if depth[0]:
                return f(*a, **k)
            depth[0] += 1
            c0 = time.process_time()
            try:
                return f(*a, **k)
            finally:
                spent[what] += time.process_time() - c0
                spent["runs"] += what == "refine"
                depth[0] -= 1

        return g

    for name in ("__init__", "reach_share", "reroute", "path", "pieces", "crosses", "flyable"):
        setattr(routing.ZoneRouter, name, timed(getattr(routing.ZoneRouter, name), "router"))
    alloc.refine_routes = timed(alloc.refine_routes, "refine")  # type: ignore[assignment]
    sc, uavs = _bench_case(case)
    cases = {"4 zones": sc, "no zones": load_scenario(*ZONE_CASES[case][:2])}
    for s in cases.values():
        alloc.make_allocation_plan(s, uavs=uavs)
    rows: dict[str, list[tuple[float, float, float, int]]] = {k: [] for k in cases}
    print("load at start", os.getloadavg(), flush=True)
    for _ in range(n):
        for label, s in cases.items():
            spent.update(refine=0.0, router=0.0, runs=0)
            c0 = time.process_time()
            plan = alloc.make_allocation_plan(s, uavs=uavs)
            total = time.process_time() - c0
            rows[label].append((total, spent["refine"], spent["router"], int(spent["runs"])))
            print(case, label, "plan CPU", round(total, 3), "refine", round(spent["refine"], 3),
                  f"({spent['runs']} runs)", "router", round(spent["router"], 3),
                  "posc", round(float(plan["posc"]), 4), flush=True)  # fmt: skip
    for label, r in rows.items():
        med = [statistics.median(x) for x in zip(*r)]
        print(f"{case} {label}: medians of {n}: plan {med[0]:.3f} s CPU, refinement "
              f"{med[1]:.3f} s ({med[3]:.0f} runs), router {med[2]:.3f} s, rest "
              f"{med[0] - med[1] - med[2]:.3f} s", flush=True)  # fmt: skip
    print("load at end", os.getloadavg(), flush=True)


def _routing_of(tree: str):
    """``poc_env/sim/routing.py`` of another source tree, loaded as its own module."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "routing_a", os.path.join(tree, "poc_env", "sim", "routing.py")
    )
    assert spec is not None and spec.loader is not None
    other = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(other)
    return other


def router(tree_a: str, case: str, n: int) -> None:
    import poc_env.sim.routing as this
    from poc_env.agents.planning.allocation import make_allocation_plan
    from poc_env.sim.core import operating_area

    other = _routing_of(tree_a)
    sc, uavs = _bench_case(case)
    calls: list[tuple[int, np.ndarray, np.ndarray]] = []
    real = this.ZoneRouter.reroute
    routers: list[int] = []

    def recorded(self, points):
        got = real(self, points)
        if id(self) not in routers:
            routers.append(id(self))
        calls.append((routers.index(id(self)), np.array(points, dtype=float), got))
        return got

    this.ZoneRouter.reroute = recorded  # type: ignore[method-assign]
    make_allocation_plan(sc, uavs=uavs)
    this.ZoneRouter.reroute = real  # type: ignore[method-assign]
    args = (sc.map.no_fly_zones_m, operating_area(sc), this.clearance_m(sc))
    cpu: dict[str, list[float]] = {tree_a: [], ".": []}
    print("load at start", os.getloadavg(), len(calls), "reroute calls", flush=True)
    for r in range(n):
        order = [(tree_a, other), (".", this)]
        for label, mod in order if r % 2 == 0 else order[::-1]:
            c0 = time.process_time()
            rs = [mod.ZoneRouter(*args) for _ in routers]
            got = [rs[i].reroute(p) for i, p, _ in calls]
            cpu[label].append(time.process_time() - c0)
            assert all(np.array_equal(g, w) for g, (_, _, w) in zip(got, calls)), label
    pairs = [round(b / a, 3) for a, b in zip(cpu[tree_a], cpu["."])]
    med = {k: round(statistics.median(v), 4) for k, v in cpu.items()}
    print(case, "router CPU s medians", med, "pair ratios this / A", pairs, "median",
          statistics.median(pairs), flush=True)  # fmt: skip
    print("load at end", os.getloadavg(), flush=True)


def plan_router(tree_a: str, case: str, n: int) -> None:
    import poc_env.agents.planning.allocation as alloc
    import poc_env.agents.planning.greedy_rectangles as greedy
    import poc_env.sim.routing as this

    other = _routing_of(tree_a)
    sc, uavs = _bench_case(case)
    ways = {tree_a: other.ZoneRouter, ".": this.ZoneRouter}

    def plan(label: str) -> dict[str, Any]:
        alloc.ZoneRouter = greedy.ZoneRouter = ways[label]  # type: ignore[misc]
        return alloc.make_allocation_plan(sc, uavs=uavs)

    print("load at start", os.getloadavg(), flush=True)
    for label in ways:
        got = plan(label)
        print(label, "digest", _digest(got), "posc", got["posc"], flush=True)
    cpu: dict[str, list[float]] = {k: [] for k in ways}
    for r in range(n):
        for label in list(ways) if r % 2 == 0 else list(ways)[::-1]:
            c0 = time.process_time()
            plan(label)
            cpu[label].append(time.process_time() - c0)
    pairs = [round(b / a, 3) for a, b in zip(cpu[tree_a], cpu["."])]
    med = {k: round(statistics.median(v), 3) for k, v in cpu.items()}
    print(case, "plan CPU s medians", med, "pair ratios this / A", pairs, "median",
          statistics.median(pairs), flush=True)  # fmt: skip
    print("load at end", os.getloadavg(), flush=True)


def timing(tree_a: str, tree_b: str, n: int, cases: list[str]) -> None:
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    print("load at start", os.getloadavg(), flush=True)
    for case in cases:
        ts: dict[str, list[float]] = {tree_a: [], tree_b: []}
        cpu: dict[str, list[float]] = {tree_a: [], tree_b: []}
        for r in range(n):
            for tree in (tree_a, tree_b):
                res = subprocess.run(
                    [sys.executable, __file__, "one", case],
                    env={**env, "PYTHONPATH": os.path.abspath(tree)},
                    capture_output=True,
                    text=True,
                    check=True,
                )
                rec = json.loads(res.stdout.strip().splitlines()[-1])
                ts[tree].append(rec["s"])
                cpu[tree].append(rec["cpu"])
                print(case, r, tree, "wall", round(rec["s"], 3), "cpu", round(rec["cpu"], 3),
                      round(rec["posc"], 4), rec["digest"],
                      "load", round(os.getloadavg()[0], 2), flush=True)  # fmt: skip
        for what, d in (("wall", ts), ("cpu", cpu)):
            ratios = [round(b / a, 3) for a, b in zip(d[tree_a], d[tree_b])]
            print(case, what, {t: round(statistics.median(x), 3) for t, x in d.items()},
                  "pair ratios B/A", ratios, "median", statistics.median(ratios),
                  flush=True)  # fmt: skip
    print("load at end", os.getloadavg(), flush=True)


if __name__ == "__main__":
    if sys.argv[1] == "digest":
        digest(sys.argv[2])
    elif sys.argv[1] == "one":
        one(sys.argv[2])
    elif sys.argv[1] == "breakdown":
        breakdown(sys.argv[2] if len(sys.argv) > 2 else "paper_6_2",
                  int(sys.argv[3]) if len(sys.argv) > 3 else 3)  # fmt: skip
    elif sys.argv[1] == "router":
        router(sys.argv[2], sys.argv[3] if len(sys.argv) > 3 else "paper_6_2",
               int(sys.argv[4]) if len(sys.argv) > 4 else 9)  # fmt: skip
    elif sys.argv[1] == "plan-router":
        plan_router(sys.argv[2], sys.argv[3] if len(sys.argv) > 3 else "paper_6_2",
                    int(sys.argv[4]) if len(sys.argv) > 4 else 8)  # fmt: skip
    elif sys.argv[1] == "profile":
        profile(sys.argv[2] if len(sys.argv) > 2 else "paper_6_2")
    else:
        timing(sys.argv[2], sys.argv[3], int(sys.argv[4]),
               sys.argv[5:] or ["paper_6_2", "large_400_160x160_24uav"])  # fmt: skip
