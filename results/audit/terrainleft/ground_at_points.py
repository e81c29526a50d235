"""i24-terrainleft: ``Terrain.ground_at`` on points reads what main's formula read (the 2 x 2
cells around each point, the grid's edges included), on 200,000 random points of a random
120 x 100 grid of 1 km cells, a thousand of them on cell edges and centres.

    .venv/bin/python results/audit/terrainleft/ground_at_points.py
"""

import numpy as np

from poc_env.agents.mission.terrain import Terrain


def main_formula(t: Terrain, xy: np.ndarray) -> np.ndarray:
    """main's ``Terrain.ground_at`` (861215b), verbatim in substance."""
    pts = np.asarray(xy, dtype=float).reshape(-1, 2)
    ny, nx = t.ground_max_m.shape
    fx = (pts[:, 0] - t.origin_m[0]) / t.cell_m - 0.5
    fy = (pts[:, 1] - t.origin_m[1]) / t.cell_m - 0.5
    i0 = np.clip(np.floor(fx).astype(int), 0, nx - 1)
    j0 = np.clip(np.floor(fy).astype(int), 0, ny - 1)
    i1, j1 = np.clip(i0 + 1, 0, nx - 1), np.clip(j0 + 1, 0, ny - 1)
    g = t.ground_max_m
    return np.maximum.reduce([g[j0, i0], g[j0, i1], g[j1, i0], g[j1, i1]])


rng = np.random.default_rng(0)
g = rng.uniform(0, 3000, (100, 120))
t = Terrain((-40e3, -30e3), 1000.0, g, g, (), 150.0, 1155.0, 6000.0, 0.26, "random")
x0, y0, x1, y1 = t.bounds
pts = np.column_stack([rng.uniform(x0 - 1, x1 + 1, 200_000), rng.uniform(y0 - 1, y1 + 1, 200_000)])
pts[:1000] = np.round(pts[:1000] / 500) * 500  # on cell edges and centres
print("points equal:", bool(np.array_equal(main_formula(t, pts), t.ground_at(pts))))

# segments up to half a cell long (a profile's sub-legs): their ground bounds the ground read
# at 2,001 points along each, and is that same ground unless a segment grazes a cell's reach
# between two of those points
a = np.column_stack([rng.uniform(x0 + 2e3, x1 - 2e3, 5000), rng.uniform(y0 + 2e3, y1 - 2e3, 5000)])
ang = rng.uniform(0, 2 * np.pi, 5000)
b = a + 500.0 * rng.uniform(0, 1, 5000)[:, None] * np.column_stack([np.cos(ang), np.sin(ang)])
seg = t.ground_at(a, b)
s = np.linspace(0.0, 1.0, 2001)
dense = np.max(t.ground_at((a[:, None, :] + (b - a)[:, None, :] * s[None, :, None]).reshape(-1, 2))
               .reshape(len(a), -1), axis=1)  # fmt: skip
print("segments bound their points:", bool(np.all(seg >= dense)),
      "equal:", int(np.sum(seg == dense)), "of", len(a))  # fmt: skip
