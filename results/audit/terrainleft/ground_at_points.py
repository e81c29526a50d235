"""i24-terrainleft: between two of its window changes (``Terrain.window_changes``) every point
of a leg reads the cells (``Terrain.ground_at``, the 2 x 2 cells around a point) its piece's
midpoint reads: 3,000 random legs up to 3 km long on a random 120 x 100 grid of 1 km cells,
2,001 points along each.

    .venv/bin/python results/audit/terrainleft/ground_at_points.py
"""

import numpy as np

from poc_env.agents.mission.terrain import Terrain

rng = np.random.default_rng(0)
g = rng.uniform(0, 3000, (100, 120))
t = Terrain((-40e3, -30e3), 1000.0, g, g, (), 150.0, 1155.0, 6000.0, 0.26, "random")
x0, y0, x1, y1 = t.bounds

# segments up to three cells long: between two of their window changes
# (Terrain.window_changes) every one of 2,001 points along them reads what the midpoint reads
a = np.column_stack([rng.uniform(x0 + 4e3, x1 - 4e3, 3000), rng.uniform(y0 + 4e3, y1 - 4e3, 3000)])
ang = rng.uniform(0, 2 * np.pi, 3000)
b = a + 3000.0 * rng.uniform(0, 1, 3000)[:, None] * np.column_stack([np.cos(ang), np.sin(ang)])
s = np.linspace(0.0, 1.0, 2001)
bad = 0
for p, q in zip(a, b):
    cuts = np.concatenate([[0.0], np.sort(t.window_changes(p, q)), [1.0]])
    reads = t.ground_at(p + (q - p) * s[:, None])
    mids = t.ground_at(p + (q - p) * ((cuts[:-1] + cuts[1:]) / 2)[:, None])
    piece = np.clip(np.searchsorted(cuts, s, side="left") - 1, 0, len(mids) - 1)
    inside = ~np.isin(s, cuts)  # the change points themselves belong to either side
    bad += int(np.sum(reads[inside] != mids[piece[inside]]))
print("points reading other cells than their piece's midpoint:", bad, "of", 3000 * 2001)
