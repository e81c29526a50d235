"""i24-cheapolish: CPU time of variants on one ``paper_6_2`` prior, in turn in one process after a
warm-up, ROUNDS rounds (a script, not a test): ``python
results/plan_scale/cheapolish/timing_prior.py SEED ROUNDS VARIANT[,VARIANT...] OUT.json``
(``effort_ab.py`` variants; the first is the reference of the ratios)."""

import json
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "..", "tests", "planning"))
from effort_ab import _options

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.config import load_scenario
from poc_env.io import write_text_atomic


def main(seed: int, rounds: int, names: list[str], out: str) -> None:
    sc = load_scenario("paper_6_2")
    prior = episode_prior(sc, seed)
    make_allocation_plan(sc, options=_options(names[-1]))  # warm-up (JIT)
    recs = []
    for r in range(rounds):
        for v in names:
            c0 = time.process_time()
            p = make_allocation_plan(sc, prior=prior, options=_options(v))
            cpu = time.process_time() - c0
            recs.append({"seed": seed, "round": r, "variant": v, "posc": float(p["posc"]),
                         "cpu_s": cpu, "load": os.getloadavg()[0]})  # fmt: skip
            print(json.dumps(recs[-1]), flush=True)
        write_text_atomic(out, json.dumps(recs, indent=1))
    for v in names[1:]:
        mine = [x["cpu_s"] for x in recs if x["variant"] == v]
        ref = [x["cpu_s"] for x in recs if x["variant"] == names[0]]
        ratio = [a / b for a, b in zip(mine, ref, strict=True)]
        print(f"{v}: CPU ratio median {statistics.median(ratio):.2f} "
              f"({min(ratio):.2f}-{max(ratio):.2f})")  # fmt: skip


if __name__ == "__main__":
    main(int(sys.argv[1]), int(sys.argv[2]), sys.argv[3].split(","), sys.argv[4])
