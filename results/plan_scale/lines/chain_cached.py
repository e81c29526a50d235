"""i24-lines: the planned loss chain (as ``effort_ab.py chain``: the planned POS stands in for
the flown) of stored plans (cache_plans.py, or stage2.py's routes), and the routes' time budget.

``python results/plan_scale/lines/chain_cached.py PLANS.json[,PLANS.json...] OUT.json``
"""

from __future__ import annotations

import json
import os
import statistics
import sys

from poc_env.agents.benchmarks.losschain import loss_chain, time_budget
from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.config import load_scenario
from poc_env.theory.probability_map import build_prior


def _load(path: str):
    with open(path) as f:
        return json.load(f)


def main(plans: list[str], out: str) -> None:
    recs = []
    for r in (r for p in plans for r in _load(p)):
        sc = load_scenario(r["map"])
        prior = build_prior(sc.map) if r["seed"] < 0 else episode_prior(sc, r["seed"])
        plan = {"uavs": r["uavs"], "posc": r["planned_posc"], "speed_rule": "max"}
        c = loss_chain(sc, prior, plan)
        b = c["values"]["bound"]
        tb = time_budget(sc, plan)
        recs.append({"map": r["map"], "seed": r["seed"], "variant": r["variant"], "bound": b,
                     "links": {k: x / b for k, x in c["links"].items()},
                     "values": {k: x / b for k, x in c["values"].items()},
                     "time": {k: x / tb["total"] for k, x in tb.items()},
                     "load": os.getloadavg()[0]})  # fmt: skip
        print(r["seed"], {k: round(x, 4) for k, x in recs[-1]["links"].items()},
              {k: round(x, 4) for k, x in recs[-1]["time"].items()}, flush=True)  # fmt: skip
        with open(out + ".tmp", "w") as f:
            json.dump(recs, f, indent=1)
        os.replace(out + ".tmp", out)
    for key in ("links", "time"):
        mean = {k: statistics.mean(r[key][k] for r in recs) for k in recs[0][key]}
        print(f"{key} (n {len(recs)}):", "; ".join(f"{k} {x:.4f}" for k, x in mean.items()))


if __name__ == "__main__":
    main(sys.argv[1].split(","), sys.argv[2])
