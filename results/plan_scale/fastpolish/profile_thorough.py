"""i24-fastpolish: where a ``thorough`` plan's time goes (a script, not a test).

``parts SEED[,SEED...] VARIANT OUT.jsonl``
    Per seed (-1: ``paper_6_2``'s own prior; else its random prior of that episode seed) one
    plan of ``VARIANT`` (``tests/planning/effort_ab.py``'s variants: ``thorough``, ...) after a
    warm-up plan (JIT), with the CPU time of each step split by plan (``options``: the
    variant's own plan; ``default``: its ``also_default`` plan) and, inside the polish, by
    stage (the polish, the second polish with block moves) and by what the polish calls
    (the exposure kernels, ``route_fits``, the airspace count and ``track``). One JSON line per
    plan. Exclusive times: a step's time excludes the wrapped steps it calls.

Run from the repository root, one thread: ``OMP_NUM_THREADS=1 python
results/plan_scale/fastpolish/profile_thorough.py parts -1,5000 thorough OUT.jsonl``.
"""

from __future__ import annotations

import collections
import json
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "..", "tests", "planning"))
from effort_ab import _options

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.config import load_scenario
from poc_env.theory.probability_map import build_prior


def _prior(sc, seed: int):
    return build_prior(sc.map) if seed < 0 else episode_prior(sc, seed)


def parts(seeds: list[int], variant: str, out: str) -> None:
    import poc_env._kernels.sensing as sens
    import poc_env.agents.planning.allocation as alloc
    import poc_env.agents.planning.polish as pol
    import poc_env.agents.planning.refine as ref

    acc: dict[str, float] = collections.defaultdict(float)
    calls: dict[str, int] = collections.defaultdict(int)
    stack: list[list] = []  # [name, start, child time]
    tag = ["?"]
    stage = [""]  # the polish stage being timed ("polish", "lines") or ""

    def wrap(mod, name: str, label=None):
        f = getattr(mod, name)

        def timed(*a, **k):
            lab = label(a, k) if label else name
            key = f"{tag[0]}:{lab}"
            if stage[0] and not lab.startswith("polish_for"):  # inside a polish stage
                key = f"{tag[0]}:{stage[0]}:{lab}"
            if lab.startswith("polish_for"):
                stage[0] = lab.split(":")[1]
            stack.append([key, time.process_time(), 0.0])
            try:
                return f(*a, **k)
            finally:
                if lab.startswith("polish_for"):
                    stage[0] = ""
                key, t0, child = stack.pop()
                dt = time.process_time() - t0
                acc[key] += dt - child
                calls[key] += 1
                if stack:
                    stack[-1][2] += dt

        setattr(mod, name, timed)

    def plan_label(a, k):
        opt = k.get("options")
        tag[0] = "options" if opt is not None and opt.graded else "default"
        return "make_allocation_plan(own)"

    def stage_label(a, k):
        return "polish_for:" + ("lines" if "block" in k.get("moves", ()) else "polish")

    wrap(alloc, "make_allocation_plan", plan_label)
    wrap(alloc, "polish_for", stage_label)
    for name in ("refine_routes", "box_routes", "sampled_sweep", "layered_tracks", "_assign",
                 "reach_optimum", "plan_geography", "make_greedy_rectangles_plan",
                 "excursion_routes", "fit_lawnmowers", "violation_penalty"):  # fmt: skip
        if hasattr(alloc, name):
            wrap(alloc, name)
    wrap(pol, "route_fits")
    wrap(pol, "track")
    wrap(pol.AirspaceCount, "move")
    wrap(pol._sensing, "exposure_gains")
    wrap(pol._sensing, "legs_exposure")
    del sens, ref
    sc = load_scenario("paper_6_2")
    alloc.make_allocation_plan(sc, refine=0)  # warm-up (JIT)
    opt = _options(variant)
    for seed in seeds:
        acc.clear()
        calls.clear()
        prior = _prior(sc, seed)
        w0, c0 = time.perf_counter(), time.process_time()
        p = alloc.make_allocation_plan(sc, prior=prior, options=opt)
        rec = {"seed": seed, "variant": variant, "wall_s": round(time.perf_counter() - w0, 3),
               "cpu_s": round(time.process_time() - c0, 3), "load": os.getloadavg()[0],
               "posc": float(p["posc"]), "kept": p["optimizer"]["settings"].get("kept"),
               "polish": p["optimizer"]["settings"].get("polish")}  # fmt: skip
        rec["parts"] = {k: round(v, 3) for k, v in sorted(acc.items(), key=lambda t: -t[1])}
        rec["calls"] = dict(calls)
        print(json.dumps(rec), flush=True)
        with open(out, "a") as f:
            f.write(json.dumps(rec) + "\n")


if __name__ == "__main__":
    cmd, *args = sys.argv[1:]
    if cmd == "parts":
        parts([int(x) for x in args[0].split(",")], args[1], args[2])
    else:
        raise SystemExit(__doc__)
