"""i24-layers: does ``separation_m = 0`` (the default) export every format byte for byte as main?

``python zero_ab.py plans DIR``: writes three plans into DIR (flat, 3 UAVs on 2 fields; the
allocation plan of ``paper_6_2`` with its CRS; the allocation plan over a 4,000 m terrain wall).
``python zero_ab.py export DIR OUT [SEP]``: exports each plan in every format into OUT (with
``separation_m=SEP`` when given, else without the keyword) and prints one JSON line per file:
name and sha256. Run ``export`` once with main's code first on the path and once with the
branch's; equal lines are equal bytes.
"""

import hashlib
import json
import sys
import warnings
from pathlib import Path

import numpy as np


def plans(d: Path) -> None:
    from poc_env.agents.mission.crs import make_crs
    from poc_env.agents.mission.plan import write_plan
    from poc_env.agents.planning.planner import make_plan
    from poc_env.agents.testing.terrain import wall_scenario
    from poc_env.config import load_scenario

    d.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(0)
    fields = ([20e3, -60e3], [150e3, -60e3], [20e3, -60e3])
    uavs = [
        {
            "id": k + 1, "rectangle": None, "spacing_m": 5e3, "takeoff_m": f, "landing_m": f,
            "waypoints_m": rng.uniform(0, 150e3, (4, 2)).round(3).tolist(),
            "track_length_m": 300e3, "flight_time_s": 9000.0, "pod": 0.79, "poc": 0.2,
            "pos": 0.158, "feasible": True,
        }
        for k, f in enumerate(fields)
    ]  # fmt: skip
    flat = {
        "schema": 2, "scenario": "paper_6_2", "seed": 1, "map_source": "builtin",
        "optimizer": {"name": "adaptive_de", "settings": {}}, "runtime_s": 0.4, "posc": 0.3,
        "upper_bound": 0.5, "uavs": uavs, "crs": make_crs("aeqd", (45.75, 126.65)),
        "flight": {"altitude_m": 1200.0, "max_altitude_m": 4000.0},
    }  # fmt: skip
    write_plan(flat, d / "flat.json")
    sc = load_scenario("paper_6_2", {"map.origin_deg": [45.75, 126.65]})
    write_plan(make_plan(sc, planner="allocation", refine=0), d / "paper.json")
    wall = load_scenario(wall_scenario())
    write_plan(make_plan(wall, planner="allocation", refine=0), d / "terrain.json")


def export(d: Path, out: Path, sep: str | None) -> None:
    from poc_env.agents.mission.export import export_plan

    kw = {} if sep is None else {"separation_m": float(sep)}
    for plan in sorted(d.glob("*.json")):
        for fmt in ("qgc", "geojson", "kml", "html"):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                files = export_plan(plan, fmt, out_dir=out / plan.stem / fmt, **kw)
            for f in sorted(files):
                sha = hashlib.sha256(f.read_bytes()).hexdigest()
                print(json.dumps({"file": f"{plan.stem}/{fmt}/{f.name}", "sha256": sha}))


if __name__ == "__main__":
    if sys.argv[1] == "plans":
        plans(Path(sys.argv[2]))
    else:
        export(Path(sys.argv[2]), Path(sys.argv[3]), sys.argv[4] if len(sys.argv) > 4 else None)
