"""A scratch check of the i25 moving-target audit (README.md)."""

import numpy as np

from poc_env.agents.planning.spacetime import spacetime_plan
from poc_env.config import load_scenario
from poc_env.theory.probability_map import Grid, build_prior

for kmh in (25, 60, 100):
    for ang in (0, 90, 180, 270):
        v = kmh / 3.6 * np.array([np.cos(np.radians(ang)), np.sin(np.radians(ang))])
        sc = load_scenario(
            "small",
            {
                "target.model": "drift",
                "target.current_kmh": [float(v[0] * 3.6), float(v[1] * 3.6)],
                "target.diffusion_m2_s": 50.0,
            },
        )
        g = Grid.from_config(sc.map)
        s = sc.sensor.samples_per_cell
        prior = build_prior(sc.map)
        plan = spacetime_plan(sc, g.refine(prior, s), v, s)
        x0, y0, x1, y1 = g.bounds
        m = sc.episode.boundary_margin_m
        wp = np.vstack([np.asarray(u["waypoints_m"]).reshape(-1, 2) for u in plan["uavs"]])
        out = np.maximum.reduce(
            [
                x0 - m - wp[:, 0],
                wp[:, 0] - x1 - m,
                y0 - m - wp[:, 1],
                wp[:, 1] - y1 - m,
                np.zeros(len(wp)),
            ]
        )
        print(
            kmh,
            ang,
            "waypoints",
            len(wp),
            "max outside op-area km",
            round(out.max() / 1e3, 2),
            "posc",
            round(plan["posc"], 3),
        )
