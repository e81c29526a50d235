"""i24-budget: digests of ``standard``'s plans on maps with no-fly zones (a script, not a test),
to check the faster polish keeps i24-zonepolish's plans bit for bit after the merge.

``python results/plan_scale/budget/zone_digest.py OUT.json`` (run from a tree's root, with
``PYTHONPATH`` on it for another tree): the property-test zone maps of seeds 5000-5005 and
``paper_6_2`` with 2 random zones, seeds 5000-5001 (``tests/planning/zone_ab.py``'s
``scenario``), planned with ``standard``: ``{case: [digest, posc]}``.
"""

import json
import os
import sys

sys.path.insert(0, os.path.join(os.getcwd(), "tests", "planning"))

from effort_ab import _digest
from zone_ab import scenario

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.options import PlanOptions
from poc_env.io import write_text_atomic


def main(out: str) -> None:
    recs = {}
    for family, seeds in (("prop", range(5000, 5006)), ("paper", range(5000, 5002))):
        for s in seeds:
            sc, prior = scenario(s, family)
            p = make_allocation_plan(sc, prior=prior, options=PlanOptions.preset("standard"))
            recs[f"{family}:{s}"] = [_digest(p), float(p["posc"])]
            print(family, s, recs[f"{family}:{s}"], flush=True)
    write_text_atomic(out, json.dumps(recs, indent=1))


if __name__ == "__main__":
    main(sys.argv[1])
