"""The final glide that meets the ground is flown, not refused (i24-glide, probe 13 of
results/audit/dayaudit), and field-mates' orbits are kept apart by their layers.

The fixture is a plan over a flat 600 m valley (an elevation grid in the scenario), taking off
at ``valley`` (-10, 20) km and landing at ``bowl`` (70, 20) km, east of the 60 x 40 km search
area. Its terrain record is then given rings of high ground round a field: a ring 6-8 km out
round ``bowl`` holds every straight approach high (from 2,100 m a 15 deg descent over the last
2 km cannot bring the UAV down to a glide from 4 km), so only a descent orbit at the approach
point lands; a ring 3-5 km out lies under every approach point and its orbit, so nothing
lands; a ring 3-4 km round ``valley`` makes both UAVs climb on a spiral over their field.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from poc_env.agents.mission.export import export_plan
from poc_env.agents.mission.formats.qgc import (
    MAV_CMD_DO_LAND_START,
    MAV_CMD_NAV_LAND,
    MAV_CMD_NAV_LOITER_TO_ALT,
    validate_qgc,
)
from poc_env.agents.mission.plan import DESCENT_KIND, load_plan, write_plan
from poc_env.agents.mission.terrain import (
    bilinear,
    from_record,
    plan_profiles,
)
from poc_env.agents.planning.planner import make_plan
from poc_env.agents.testing.terrain import VALLEY_M, ring_around, wall_scenario
from poc_env.config import load_scenario
from poc_env.errors import ConfigError

BOWL_KM = (70.0, 20.0)
VALLEY_KM = (-10.0, 20.0)


@pytest.fixture(scope="module")
def bowl_plan() -> dict:
    """A 2-UAV allocation plan over a flat valley, valley -> bowl."""
    flat = {"elevation_m": np.full((100, 140), VALLEY_M).tolist(), "cell_km": 1.0,
            "origin_km": [-40, -30]}  # fmt: skip
    sc = load_scenario(wall_scenario(
        airfields=[{"name": "valley", "position_km": list(VALLEY_KM)},
                   {"name": "bowl", "position_km": list(BOWL_KM)}],
        fleet=[{"takeoff": "valley", "landing": "bowl", "count": 2}], terrain=flat,
    ))  # fmt: skip
    return make_plan(sc, planner="allocation", uavs=2, refine=0)


def test_a_glide_over_high_ground_lands_on_a_descent_orbit(tmp_path, bowl_plan):
    """Before (main at ab33f59) this plan was refused by every export ("a glide to the landing
    field within eq. 19's pitch bound ..."). Now each UAV descends on NAV_LOITER_TO_ALT at its
    approach point (DO_LAND_START, the approach waypoint, the orbit, NAV_LAND: PX4's landing
    pattern) and glides from the orbit's tangent exit at the flat export's slope; the orbit
    and the glide keep the ground, every mission point keeps the clearance."""
    plan = ring_around(bowl_plan, BOWL_KM, 6.0, 8.0, VALLEY_M + 1500.0)
    write_plan(plan, tmp_path / "plan.json")
    loaded = load_plan(tmp_path / "plan.json")
    t = from_record(loaded["terrain"])
    profs = plan_profiles(loaded)
    field = np.asarray(BOWL_KM) * 1e3
    bowl = [k for k, u in enumerate(plan["uavs"]) if np.allclose(u["landing_m"], field)]
    assert profs is not None and bowl  # the UAVs the plan lands at bowl
    assert all((profs[k].descent is not None) == (k in bowl) for k in range(len(profs)))
    for p in (profs[k] for k in bowl):
        d = p.descent
        o = d.orbit
        xy, z = d.points()
        ground = bilinear(t.ground_m, t.origin_m, t.cell_m, xy)
        assert np.all(z - ground >= t.min_clearance_m - 1e-6)  # every point of the orbit
        assert np.all(p.amsl_m - p.ground_m >= t.min_clearance_m - 1e-6)  # and of the route
        c = np.asarray(o.center_m)
        assert np.hypot(*(field - c)) == pytest.approx(4000.0)  # the approach point
        assert d.glide_m == pytest.approx(math.sqrt(4000.0**2 - o.radius_m**2))
        slope = (o.to_m - p.landing_field_m) / d.glide_m  # PX4's reading of the glide
        assert slope <= 300.0 / 4000.0 + 1e-9
        exit_xy = np.asarray(d.exit_m)
        assert np.dot(exit_xy - c, field - exit_xy) == pytest.approx(0.0, abs=1e-3)  # tangent
        s = np.linspace(0.0, 1.0, 200)[:, None]
        line = exit_xy + (field - exit_xy) * s
        under = bilinear(t.ground_m, t.origin_m, t.cell_m, line)
        assert np.all(o.to_m + (p.landing_field_m - o.to_m) * s[:, 0] > under - 1e-6)

    for fmt in ("qgc", "kml", "geojson", "html"):
        export_plan(tmp_path / "plan.json", fmt, out_dir=tmp_path / fmt)
    for u, p in ((plan["uavs"][k], profs[k]) for k in bowl):
        doc = json.loads((tmp_path / "qgc" / f"plan_uav{u['id']}.plan").read_text())
        assert validate_qgc(doc) == []
        cmds = [it["command"] for it in doc["mission"]["items"]]
        i = cmds.index(MAV_CMD_DO_LAND_START)
        assert cmds[i + 2 :] == [MAV_CMD_NAV_LOITER_TO_ALT, MAV_CMD_NAV_LAND]
        loiter = doc["mission"]["items"][i + 2]
        assert loiter["params"][4:6] == doc["mission"]["items"][i + 1]["params"][4:6]
        assert loiter["params"][:4] == [1, round(p.descent.orbit.radius_m, 1), 0, 1]
        assert loiter["params"][6] == round(p.descent.orbit.to_m, 1)
    gj = json.loads(next((tmp_path / "geojson").glob("*.geojson")).read_text())
    descents = [f for f in gj["features"] if f["properties"]["kind"] == DESCENT_KIND]
    assert len(descents) == len(bowl)
    assert b"descent orbit" in next((tmp_path / "kml").glob("*.kml")).read_bytes()
    assert b"descent orbit" in next((tmp_path / "html").glob("*.html")).read_bytes()


def test_no_side_of_the_field_clears_refused_naming_the_uav(tmp_path, bowl_plan):
    """High ground under every approach point and its orbit: every format refuses, naming the
    UAV and the sides tried; nothing is written."""
    plan = ring_around(bowl_plan, BOWL_KM, 3.0, 5.0, VALLEY_M + 1500.0)
    write_plan(plan, tmp_path / "plan.json")
    field = np.asarray(BOWL_KM) * 1e3
    k = next(k for k, u in enumerate(plan["uavs"]) if np.allclose(u["landing_m"], field))
    uid = plan["uavs"][k]["id"]
    for fmt in ("qgc", "kml", "geojson", "html"):
        with pytest.raises(
            ConfigError, match=rf"plan\.uavs\[{k}\] \(UAV {uid}\).*no side of the landing field"
        ):
            export_plan(tmp_path / "plan.json", fmt, out_dir=tmp_path / fmt)
        assert not (tmp_path / fmt).exists()


def test_field_mates_orbits_are_kept_apart_by_their_layers(tmp_path, bowl_plan, capsys):
    """Both UAVs of ``valley`` climb on a spiral over it (a ring 2.5-4.5 km out; the plan's
    fields edited: both take off at ``valley`` and land at ``bowl``): without layers they
    orbit one circle, and the export says so (a warning naming both); with ``--separation-m
    S`` UAV k' orbits ``k' x S`` wider, so every point of one orbit is at least S from every
    point of the other."""
    plan = ring_around(bowl_plan, VALLEY_KM, 2.5, 4.5, VALLEY_M + 1200.0)
    start = [float(v) * 1e3 for v in VALLEY_KM]
    bowl = [float(v) * 1e3 for v in BOWL_KM]  # both land at bowl (the ring is on no glide)
    plan = {**plan, "uavs": [{**u, "takeoff_m": start, "landing_m": bowl} for u in plan["uavs"]]}
    write_plan(plan, tmp_path / "plan.json")
    sep = 30.0
    radii, said = {}, {}
    for tag, opts in (("flat", {}), ("lay", {"separation_m": sep})):
        capsys.readouterr()
        export_plan(tmp_path / "plan.json", "qgc", out_dir=tmp_path / tag, **opts)
        said[tag] = capsys.readouterr().err
        export_plan(tmp_path / "plan.json", "geojson", out_dir=tmp_path / f"{tag}_gj", **opts)
        radii[tag] = []
        for u in plan["uavs"]:
            doc = json.loads((tmp_path / tag / f"plan_uav{u['id']}.plan").read_text())
            (orbit,) = [
                it for it in doc["mission"]["items"] if it["command"] == MAV_CMD_NAV_LOITER_TO_ALT
            ]
            radii[tag].append(orbit["params"][1])
    assert radii["flat"][0] == radii["flat"][1]  # without layers: one circle, said
    ids = ", ".join(str(u["id"]) for u in plan["uavs"])
    assert f"warning: UAVs {ids} fly one climb spiral over the take-off field" in said["flat"]
    assert "fly one climb spiral" not in said["lay"]  # (the rates warning names spirals too)
    assert abs(radii["lay"][1] - radii["lay"][0]) >= sep - 0.1
    gj = json.loads(next((tmp_path / "lay_gj").glob("*.geojson")).read_text())
    orbits = [f for f in gj["features"] if f["properties"]["kind"] == "climb_spiral"]
    assert len(orbits) == 2
    a, b = (np.radians(np.asarray(f["geometry"]["coordinates"])[:, :2]) for f in orbits)
    # planar distances on the local tangent plane (metres) between every pair of points
    r_e = 6_371_000.0
    lat0 = float(a[0, 1])
    pa = np.column_stack([a[:, 0] * math.cos(lat0), a[:, 1]]) * r_e
    pb = np.column_stack([b[:, 0] * math.cos(lat0), b[:, 1]]) * r_e
    gap = np.min(np.hypot(*(pa[:, None, :] - pb[None, :, :]).transpose(2, 0, 1)))
    assert gap >= sep - 1.0
