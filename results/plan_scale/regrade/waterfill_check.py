"""i24-regrade: the water-filled offsets of each run of ``standard``'s routes on ``paper_6_2``'s
own prior (stored in val_standard_paper_6_2.json): per run, the mass left per sample row across
it (relative to its largest) and the water-filled offsets (km from the rows' first edge).
``python results/plan_scale/regrade/waterfill_check.py``"""

from __future__ import annotations

import json
import os

import numpy as np

import poc_env.agents.planning.regrade as R
from poc_env.agents.planning.polish import polish_for
from poc_env.config import load_scenario
from poc_env.theory.probability_map import build_prior

_graded = R.graded_offsets


def _spy(rows, *a, **k):
    out = _graded(rows, *a, **k)
    m = rows[:, 0]
    print("rows", np.round(m / m.max(), 2).tolist(), "lines", a[2], "-> offsets km",
          np.round(out / 1000, 1).tolist())  # fmt: skip
    return out


R.graded_offsets = _spy
with open(os.path.join(os.path.dirname(__file__), "val_standard_paper_6_2.json")) as f:
    r = json.load(f)[0]
sc = load_scenario("paper_6_2")
routes = [u["waypoints_m"] for u in r["uavs"]]
out = polish_for(sc, routes, build_prior(sc.map), 1, routine=R.regrade_routes, counts=(0,),
                 sweeps=0, min_lines=3)  # fmt: skip
print("planned POS", out[1], "against", r["planned_posc"], out[2])
