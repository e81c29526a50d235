"""i24-terrainleft item 6: one long profile (59 random legs, 14,214 km, over a random 500 x 500
grid of 1 km cells), timed by main's and the branch's venv in turn:

    B=/work/wt/i24-terrainleft/results/audit/terrainleft
    cd /work/main && .venv/bin/python $B/long_profile.py
    cd /work/wt/i24-terrainleft && .venv/bin/python results/audit/terrainleft/long_profile.py
"""

import time

import numpy as np

from poc_env.agents.mission.terrain import Terrain, profile

rng = np.random.default_rng(1)
g = rng.uniform(0, 3000, (500, 500))
t = Terrain((0.0, 0.0), 1000.0, g, g, (), 150.0, 1155.0, 6000.0, 0.26, "random")
path = rng.uniform(5e3, 495e3, (60, 2))
length = float(np.sum(np.hypot(*np.diff(path, axis=0).T)))
t0 = time.perf_counter()
p = profile(t, path, "UAV 1")
took = time.perf_counter() - t0
print(f"route {length / 1e3:.0f} km, {len(p.amsl_m)} points kept, {took:.2f} s")
