"""i24-orbitfit: write test_orbit_fit's ring scenario (valley -> bowl, a 3,100 m ring 6-8 km
round bowl) as YAML, for ``poc-env plan --fleet-sizes``.

Usage: python results/mission/i24-orbitfit/fleet_ring.py OUT.yaml
"""

import sys
from pathlib import Path

import numpy as np
import yaml

from poc_env.agents.testing.terrain import VALLEY_M, wall_scenario

x = -40 + np.arange(140) + 0.5
y = -30 + np.arange(100) + 0.5
gx, gy = np.meshgrid(x, y)
d = np.hypot(gx - 70, gy - 20)
elev = np.where((d >= 6) & (d <= 8), VALLEY_M + 2500.0, np.full(gx.shape, VALLEY_M))
sc = wall_scenario(
    airfields=[{"name": "valley", "position_km": [-10, 20]},
               {"name": "bowl", "position_km": [70, 20]}],
    fleet=[{"takeoff": "valley", "landing": "bowl", "count": 2}],
    terrain={"elevation_m": elev.tolist(), "cell_km": 1.0, "origin_km": [-40, -30]},
)  # fmt: skip
Path(sys.argv[1]).write_text(yaml.safe_dump(sc))
