"""i24-terrainleft: one probe per item, run on main and on the branch (each checkout's venv):

    cd /work/main && .venv/bin/python /work/wt/i24-terrainleft/results/audit/terrainleft/probes.py
    cd /work/wt/i24-terrainleft && .venv/bin/python results/audit/terrainleft/probes.py

Prints one JSON line per probe: what the code did (accepted / the error's first 300 characters).
"""

from __future__ import annotations

import json
import tempfile
import warnings
from pathlib import Path

import numpy as np

from poc_env.config import load_scenario
from poc_env.errors import ConfigError, GeometryError

warnings.simplefilter("ignore")
VALLEY = 600.0


def _scenario(terrain: dict) -> dict:
    return {
        "name": "alps",
        "map": {"width_km": 60, "height_km": 40, "cell_km": 5, "origin_deg": [46.5, 7.9],
                "prior": {"components": [{"mean_km": [32, 20], "sigma_km": [10, 8]}]}},
        "airfields": [{"name": "valley", "position_km": [-10, 20]}],
        "fleet": [{"takeoff": "valley", "count": 2}],
        "uav": {"max_altitude_m": 6000},
        "terrain": terrain,
    }  # fmt: skip


def _outcome(fn) -> str:
    try:
        fn()
    except (ConfigError, GeometryError) as err:
        return "refused: " + str(err)[:300]
    return "accepted"


def climb() -> dict:
    """#1: ground rising 400 m/km east of the field (steeper than the 268 m/km a 15 deg climb
    gains); and flat 600 m ground with a 900 m rise 2-3 km out under the final glide."""
    from poc_env.agents.mission.terrain import load_terrain, profile

    x = -40 + np.arange(120) + 0.5
    slope = np.tile(np.minimum(VALLEY + 400.0 * (x + 10.0), 5000.0), (100, 1)).tolist()
    bump = np.tile(np.where(np.abs(x + 7.5) < 0.5, 900.0, VALLEY), (100, 1)).tolist()
    field = [-10e3, 20e3]

    def load(grid):
        sc = load_scenario(_scenario({"elevation_m": grid, "cell_km": 1.0,
                                      "origin_km": [-40, -30]}))  # fmt: skip
        return load_terrain(sc)

    route = [field, [10e3, 20e3], [10e3, 25e3], [-6e3, 20e3]]
    return {
        "climb_400m_per_km": _outcome(lambda: profile(load(slope), route, "UAV 1")),
        "glide_over_900m_rise": _outcome(lambda: profile(load(bump), route, "UAV 1", field)),
    }


def datum(tmp: Path) -> dict:
    """#2: the same DEM declared in EPSG:4979 (ellipsoidal heights) and EPSG:4326+5773 (EGM96)."""
    import rasterio
    from rasterio.transform import from_origin

    from poc_env.agents.mission.terrain import load_terrain

    out = {}
    for crs in ("EPSG:4326", "EPSG:4979", "EPSG:4326+5773"):
        path = tmp / f"dem_{crs.replace(':', '').replace('+', '_')}.tif"
        with rasterio.open(path, "w", driver="GTiff", width=460, height=240, count=1,
                           dtype="float32", crs=crs,
                           transform=from_origin(7.0, 47.1, 0.005, 0.005)) as dst:  # fmt: skip
            dst.write(np.full((240, 460), VALLEY, "float32"), 1)
        out[crs] = _outcome(lambda p=path: load_terrain(load_scenario(_scenario({"dem": str(p)}))))
    return out


def reach() -> dict:
    """#3: the bounds' zone reach at 16 x 16 samples a cell under a 0.1 MiB memory limit."""
    from poc_env import limits
    from poc_env.theory.bound import zone_reach
    from poc_env.theory.probability_map import Grid

    sc = load_scenario("small", {"map.no_fly_zones_km": [[[5, 5], [35, 5], [35, 35], [5, 35]]],
                                 "sensor.samples_per_cell": 16})  # fmt: skip
    prior = np.ones(Grid.from_config(sc.map).shape)
    with limits.memory_limit_gb(0.1 / 1024):
        return {"zone_reach_s16_limit_0.1MiB": _outcome(lambda: zone_reach(sc, prior))}


def antimeridian(tmp: Path) -> dict:
    """#4: an area near Fiji crossing 180, cut there into a MultiPolygon (RFC 7946 3.1.9)."""
    from poc_env.agents.mission.geoimport import import_scenario

    west = [[178.5, -17.5], [180.0, -17.5], [180.0, -16.5], [178.5, -16.5], [178.5, -17.5]]
    east = [[-180.0, -17.5], [-178.5, -17.5], [-178.5, -16.5], [-180.0, -16.5], [-180.0, -17.5]]
    area = tmp / "fiji.geojson"
    area.write_text(json.dumps({"type": "Feature", "properties": {}, "geometry": {
        "type": "MultiPolygon", "coordinates": [[west], [east]]}}))  # fmt: skip
    fields = tmp / "f.geojson"
    fields.write_text(
        json.dumps(
            {
                "type": "Feature",
                "properties": {"name": "Labasa"},
                "geometry": {"type": "Point", "coordinates": [-179.9, -16.3]},
            }
        )
    )
    got: dict = {}

    def run():
        got["r"] = import_scenario(area, airfields=fields, cell_km=10)

    out = {"fiji_cut_multipolygon": _outcome(run)}
    if "r" in got:
        r = got["r"]
        out["area_km2"] = round(r["report"]["area_km2"], 1)
        out["origin_deg"] = r["crs"]["origin_deg"]
        out["grid"] = [r["scenario"]["map"]["width_km"], r["scenario"]["map"]["height_km"]]
    return out


if __name__ == "__main__":
    with tempfile.TemporaryDirectory() as d:
        for name, res in (("1 climb/glide", climb()), ("2 vertical datum", datum(Path(d))),
                          ("3 zone_reach guard", reach()),
                          ("4 antimeridian import", antimeridian(Path(d)))):  # fmt: skip
            print(json.dumps({"item": name, **res}))
