"""Terrain follow-up 2: ``replan --tracks`` of a plan's own KML/GeoJSON, before and after.

Plans ``small`` (allocation, origin 46.5,7.9) and the terrain test scenario (the Alps DEM of
tests/mission/test_terrain.py, allocation, refine 0), exports KML and GeoJSON, reads them as
tracks (this branch: the landing approaches skipped) and sweeps them by eq. 14
(``searched_belief``); "as main" sweeps the same tracks plus the skipped approach lines (what
main read). Usage: ``python replan_own_export.py OUT.json`` from the repository root.
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, "tests/mission")


def main(out: str) -> None:
    import test_terrain as T

    from poc_env.agents.mission.crs import to_local
    from poc_env.agents.mission.export import export_plan
    from poc_env.agents.mission.features import overlays
    from poc_env.agents.mission.plan import write_plan
    from poc_env.agents.planning.planner import make_plan
    from poc_env.agents.planning.replan import plan_paths, read_tracks, searched_belief
    from poc_env.config import load_scenario
    from poc_env.theory.probability_map import build_prior

    tmp = Path(tempfile.mkdtemp())
    cases = {
        "small": (load_scenario("small"), {"origin_deg": (46.5, 7.9)}),
        "alps_dem": (load_scenario(T._scenario(T._dem(tmp / "d.tif"))), {}),
    }
    recs = []
    for name, (sc, kw) in cases.items():
        plan = make_plan(sc, planner="allocation", refine=0, **kw)
        write_plan(plan, tmp / f"{name}.json")
        prior = build_prior(sc.map)
        _, routes = searched_belief(sc, prior, plan_paths(plan))
        apps = [
            np.array(to_local(o["latlon"], plan["crs"]))
            for o in overlays(plan, plan["crs"], 0.0, 0.0)
            if o["properties"]["kind"] == "landing_approach"
        ]
        for fmt in ("kml", "geojson"):
            files = export_plan(tmp / f"{name}.json", fmt, out_dir=tmp / f"{name}_{fmt}")
            (f,) = [p for p in files if p.suffix == "." + fmt]
            skipped: list[str] = []
            tracks = [t for _, t in read_tracks(f, plan["crs"], skipped)]
            _, branch = searched_belief(sc, prior, tracks)
            _, as_main = searched_belief(sc, prior, tracks + apps)
            recs.append({"scenario": name, "format": fmt, "uavs": len(plan["uavs"]),
                         "tracks_branch": len(tracks), "approaches_skipped": len(skipped),
                         "tracks_main": len(tracks) + len(skipped), "posc_plan": plan["posc"],
                         "searched_routes": routes, "searched_branch": branch,
                         "searched_as_main": as_main})  # fmt: skip
            print(json.dumps(recs[-1]))
    Path(out).write_text(json.dumps(recs, indent=1) + "\n")


if __name__ == "__main__":
    main(sys.argv[1])
