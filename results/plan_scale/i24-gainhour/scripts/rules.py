"""i24-gainhour, G3: candidate stay-home rules planned and flown (a script, not a test).

``python rules.py OUT.json CASES RULE [RULE ...]``: at the measurement commit 976da86 (its
``allocation.HOME_RULE`` seam) every rule; after it (the final code keeps the chosen rule
only) ``hourG`` and ``off``. CASES: ``big24``,
``big48`` (the 500 km scenario at ``/tmp/gainhour/big.yaml`` with ``with_uavs(N)``, flown once,
seed 5000) or ``paper`` (``paper_6_2``'s validation priors 5000-5009, each flown with its own
prior and seed). RULE: ``budget`` (main: 1e-4 of the mass a loss budget for the plan),
``uav`` (a floor of 1e-4 per UAV, no budget, longest flight tried first), ``hourG`` (a floor
of G per flight hour, no budget; at 976da86 least POS per hour tried first, after it longest
flight first), ``off`` (``PlanOptions(nothing=0)``: every route).
Per case and rule: digest, planned and flown POS_C, UAVs flying, flight hours, no-fly and
collision steps, the UAVs kept home by the rule; OUT.json rewritten after each.
"""

import json
import math
import sys
import time
from pathlib import Path

import poc_env.agents.planning.allocation as al
from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.agents.planning.options import PlanOptions
from poc_env.agents.testing.flights import fly
from poc_env.config import load_scenario

sys.path.insert(0, str(Path(__file__).resolve().parents[4] / "tests" / "planning"))
sys.path.insert(0, str(Path(__file__).resolve().parents[4] / "results/audit/i24-smallfix/scripts"))
from ab_f1 import record
from flyseeds import Saved

BIG = "/tmp/gainhour/big.yaml"


def rule(name: str):
    """(options, HOME_RULE) of a rule's name: after the measurement commit (no seam) the
    ``hourG`` rules are ``PlanOptions(gain_per_hour=G)`` (the final code: longest flight
    first) and ``off`` ``PlanOptions(nothing=0)``."""
    if not hasattr(al, "HOME_RULE"):
        if name.startswith("hour"):
            return PlanOptions(gain_per_hour=float(name[4:])), None
        if name == "off":
            return PlanOptions(nothing=0.0), None
        raise SystemExit(f"{name}: only at the measurement commit 976da86")
    if name == "budget":
        return PlanOptions(), lambda o: (o.nothing, 0.0, o.nothing, "hours")
    if name == "off":
        return PlanOptions(nothing=0.0), lambda o: (0.0, 0.0, 0.0, "hours")
    if name == "uav":
        return PlanOptions(), lambda o: (1e-4, 0.0, math.inf, "hours")
    if name.startswith("hour"):
        g = float(name[4:])
        return PlanOptions(), lambda o: (0.0, g, math.inf, "gain")
    raise SystemExit(f"unknown rule {name}")


def low(sc, prior, p) -> list:
    """Each flying UAV crediting below 1e-3 (first-to-last): id, hours, its marginal planned
    POS (the sampled eq. 14 total less the total without it; dayaudit2's marginal.py)."""
    from poc_env.theory.probability_map import Grid, build_prior

    grid = Grid.from_config(sc.map)
    prior = build_prior(sc.map) if prior is None else prior
    paths = [[u["takeoff_m"], *u["waypoints_m"], u["landing_m"]] if u["waypoints_m"] else []
             for u in p["uavs"]]  # fmt: skip
    pos, _ = al.sampled_sweep(sc, grid, prior, paths)
    out = []
    for k, u in enumerate(p["uavs"]):
        if u["waypoints_m"] and pos[k] < 1e-3:
            rest = [q if j != k else [] for j, q in enumerate(paths)]
            m = sum(pos) - sum(al.sampled_sweep(sc, grid, prior, rest)[0])
            out.append([u["id"], u["flight_time_s"] / 3600, m])
    return out


def cases(which: str):
    if which.startswith("big"):
        n = int(which[3:])
        yield f"big:{n}", load_scenario(BIG).with_uavs(n), None, 5000
    elif which == "paper":
        sc = load_scenario("paper_6_2")
        for s in range(5000, 5010):
            yield f"paper_6_2:{s}", sc, episode_prior(sc, s), s


if __name__ == "__main__":
    out = Path(sys.argv[1])
    recs = json.loads(out.read_text()) if out.exists() else {}
    for key, sc, prior, seed in cases(sys.argv[2]):
        for name in sys.argv[3:]:
            opt, seam = rule(name)
            if seam is not None:
                al.HOME_RULE = seam
            t = time.perf_counter()
            p = al.make_allocation_plan(sc, prior=prior, options=opt)
            rec = record(p, t)  # digest, posc, start, flying, hours, plan_s, load
            r = fly(sc, Saved(p), seed=seed, prior=prior)
            rec |= {"planned": rec.pop("posc"), "flown": r.posc, "nofly_steps": r.nofly_steps,
                    "collision_steps": r.collision_steps, "landed": r.landed,
                    "home": p["optimizer"]["settings"].get("home", []),
                    "low": low(sc, prior, p)}  # fmt: skip
            recs[f"{key}:{name}"] = rec
            print(key, name, {k: v for k, v in rec.items() if k != "home"},
                  "home", [(h["id"], round(h["hours"], 2), f"{h['pos']:.1e}") for h in rec["home"]],
                  "low", [(i, round(h, 2), f"{m:.1e}") for i, h, m in rec["low"]],
                  flush=True)  # fmt: skip
            out.write_text(json.dumps(recs, indent=1))
