"""Terrain follow-up 1: the altitude properties of the GeoJSON routes of the terrain test
scenario's plan (the Alps DEM of tests/mission/test_terrain.py, allocation, refine 0) against
the z their lines carry. Usage: ``python geojson_route_props.py`` from the repository root."""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, "tests/mission")


def main() -> None:
    import test_terrain as T

    from poc_env.agents.mission.export import export_plan
    from poc_env.agents.mission.plan import write_plan
    from poc_env.agents.planning.planner import make_plan
    from poc_env.config import load_scenario

    tmp = Path(tempfile.mkdtemp())
    sc = load_scenario(T._scenario(T._dem(tmp / "d.tif")))
    write_plan(make_plan(sc, planner="allocation", refine=0), tmp / "plan.json")
    (f,) = export_plan(tmp / "plan.json", "geojson", out_dir=tmp / "g")
    for ft in json.loads(f.read_text())["features"]:
        p = ft["properties"]
        if p["kind"] != "route":
            continue
        z = [c[2] for c in ft["geometry"]["coordinates"]]
        keys = ("altitude_m", "search_height_m", "min_clearance_m", "altitude_min_m",
                "altitude_max_m", "altitude_ref")  # fmt: skip
        shown = {k: p[k] for k in keys if k in p}
        print(
            f"UAV {p['id']}: {shown}; airborne z {min(z[1:-1]):.1f}-{max(z[1:-1]):.1f} m, "
            f"fields {z[0]:.1f} / {z[-1]:.1f} m"
        )


if __name__ == "__main__":
    main()
