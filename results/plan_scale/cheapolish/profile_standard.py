"""i24-cheapolish: where `standard`'s time goes on ``paper_6_2`` (a script, not a test).

``python results/plan_scale/cheapolish/profile_standard.py SEEDS OUT.json [VARIANT]``
(SEEDS comma-separated, -1 the map's own prior): per prior, after a warm-up, the default plan
(CPU time), then ``VARIANT``'s (default ``standard``) polish stages replayed from its routes with
:func:`~poc_env.agents.planning.polish.polish_for` as the planner calls them (checked: the
same routes and planned POS as ``make_allocation_plan`` with the variant's options), with a
``trace`` that charges the CPU time since the previous choice to each choice of a set of
candidates: per stage, pass and kind the choices, candidates, kept moves and CPU time; and the
kept candidates' indices per kind and window (which radii / directions / factors are kept).
"""

import json
import os
import sys
import time
from collections import defaultdict

sys.path.insert(0, "tests/planning")

from effort_ab import _digest, _options

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.polish import KINDS, MOVES, polish_for
from poc_env.config import load_scenario
from poc_env.io import write_text_atomic
from poc_env.theory.probability_map import build_prior


def stages(opt):
    moves = KINDS if opt.polish_grade else MOVES
    out = []
    if opt.polish:
        out.append(("polish", opt.polish, moves, opt.polish_radii))
    if opt.polish_lines:
        out.append(("lines", opt.polish_lines, (*moves, "block"), opt.polish_lines_radii))
    return out


def main(seeds, out, variant="standard"):
    sc = load_scenario("paper_6_2")
    opt = _options(variant)
    make_allocation_plan(sc, options=opt)  # warm-up
    recs = []
    for seed in seeds:
        prior = build_prior(sc.map) if seed < 0 else episode_prior(sc, seed)
        c0 = time.process_time()
        base = make_allocation_plan(sc, prior=prior)
        c_default = time.process_time() - c0
        c0 = time.process_time()
        ref = make_allocation_plan(sc, prior=prior, options=opt)
        c_variant = time.process_time() - c0
        routes = [u["waypoints_m"] for u in base["uavs"]]
        cost: dict = defaultdict(lambda: [0, 0, 0, 0.0, 0.0])  # calls, cands, kept, cpu, gain
        kept_idx: dict = defaultdict(lambda: defaultdict(int))
        clock = [0.0]
        stage_name = [""]

        def trace(kind, pss, k, i, window, n, kept, gain, cost=cost, kept_idx=kept_idx,
                  clock=clock, stage_name=stage_name):  # fmt: skip
            now = time.process_time()
            row = cost[f"{stage_name[0]}:{pss}:{kind}"]
            row[0] += 1
            row[1] += n
            row[2] += kept >= 0
            row[3] += now - clock[0]
            row[4] += gain
            clock[0] = now
            if kept >= 0:
                kept_idx[f"{stage_name[0]}:{kind}:{window}:{n}"][kept] += 1

        setup = {}
        for name, passes, moves, radii in stages(opt):
            stage_name[0] = name
            c0 = time.process_time()
            clock[0] = c0
            kw = {"block_windows": opt.polish_lines_windows,
                  "block_radii": opt.polish_lines_block_radii or None}  # fmt: skip
            routes, _, stats = polish_for(sc, routes, prior, passes, moves=moves, radii=radii,
                                          trace=trace, **kw)  # fmt: skip
            setup[name] = {"cpu_s": time.process_time() - c0, "stats": stats}
        same = [[list(map(float, w)) for w in r] for r in routes] == [
            u["waypoints_m"] for u in ref["uavs"]
        ]
        rec = {"seed": seed, "variant": variant, "cpu_default": c_default,
               "cpu_variant": c_variant, "replay_same_routes": same,
               "stages": setup, "cost": dict(cost),
               "kept_idx": {k: dict(v) for k, v in kept_idx.items()},
               "digest": _digest(ref), "load": os.getloadavg()[0]}  # fmt: skip
        recs.append(rec)
        print(seed, variant, f"default {c_default:.2f} s, variant {c_variant:.2f} s, "
              f"replay same {same}, load {rec['load']:.1f}", flush=True)  # fmt: skip
        for key, (calls, cands, kept, cpu, gain) in sorted(cost.items()):
            print(
                f"  {key:24s} calls {calls:5d} cands {cands:6d} kept {kept:4d} "
                f"cpu {cpu:6.3f} s  per kept {cpu / max(kept, 1) * 1e3:7.1f} ms gain {gain:.5f}",
                flush=True,
            )
        write_text_atomic(out, json.dumps(recs, indent=1))


if __name__ == "__main__":
    main([int(s) for s in sys.argv[1].split(",")], sys.argv[2], *sys.argv[3:])
