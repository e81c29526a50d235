"""A scratch check of the i25 moving-target audit (README.md)."""

import sys

import numpy as np

from poc_env.agents.planning.spacetime import spacetime_plan
from poc_env.config import load_scenario
from poc_env.theory.probability_map import Grid, build_prior

name = sys.argv[1]
kmh = float(sys.argv[2])
for ang in range(0, 360, 45):
    v = kmh / 3.6 * np.array([np.cos(np.radians(ang)), np.sin(np.radians(ang))])
    sc = load_scenario(
        name,
        {
            "target.model": "drift",
            "target.current_kmh": [float(v[0] * 3.6), float(v[1] * 3.6)],
            "target.diffusion_m2_s": 50.0,
        },
    )
    g = Grid.from_config(sc.map)
    s = sc.sensor.samples_per_cell
    plan = spacetime_plan(sc, g.refine(build_prior(sc.map), s), v, s)
    print(name, kmh, ang, "cut", plan.get("cut_outside_area", 0), flush=True)
