"""A take-off climb that meets the ground is flown on a spiral over the field (issue 24, F3 of
results/audit/dayaudit): the mission exports with a NAV_LOITER_TO_ALT whose every point keeps
the clearance, the spiral's time is charged against eq. 18's 0.85 T (refused naming the UAV
and the minutes missing), and a mission whose straight climb clears exports as before.

The fixture is a plan over a flat 600 m valley (an elevation grid in the scenario) whose
terrain record is given a 2,500 m wall across one UAV's first leg, 3-4 km from its field:
beyond the orbit's radius (220 km/h at 3 deg/s: 1.17 km), within the straight climb's reach
(600 m + tan 15 deg x 3 km = 1,404 m).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from poc_env.agents.mission.export import export_plan
from poc_env.agents.mission.formats.kml import validate_kml
from poc_env.agents.mission.formats.qgc import MAV_CMD_NAV_LOITER_TO_ALT, validate_qgc
from poc_env.agents.mission.plan import CLIMB_KIND, load_plan, write_plan
from poc_env.agents.mission.terrain import bilinear, from_record, mission_path, plan_profiles
from poc_env.agents.planning.planner import make_plan
from poc_env.agents.testing.terrain import VALLEY_M, hill_across_first_leg, wall_scenario
from poc_env.config import load_scenario
from poc_env.errors import ConfigError

WALL_M = 2500.0


@pytest.fixture(scope="module")
def flat_plan() -> dict:
    """A 2-UAV allocation plan over a flat valley (120 x 100 cells of 1 km from (-40, -30) km),
    taking off at x = -10 km and landing at x = 60 km (so the wall is on no final glide)."""
    flat = {"elevation_m": np.full((100, 120), VALLEY_M).tolist(), "cell_km": 1.0,
            "origin_km": [-40, -30]}  # fmt: skip
    sc = load_scenario(wall_scenario(
        airfields=[{"name": "valley", "position_km": [-10, 20]},
                   {"name": "east", "position_km": [60, 20]}],
        fleet=[{"takeoff": "valley", "landing": "east", "count": 2}], terrain=flat,
    ))  # fmt: skip
    return make_plan(sc, planner="allocation", uavs=2, refine=0)


def _walled(plan: dict) -> tuple[dict, int]:
    """``plan`` with a 2,500 m wall across the longest first leg, 3-4 km from the field, and
    that UAV's index."""
    legs = [np.hypot(*np.subtract(u["waypoints_m"][0], u["takeoff_m"])) for u in plan["uavs"]]
    k = int(np.argmax(legs))
    rec = hill_across_first_leg(plan, k, 3e3, 4e3, 500.0, WALL_M)
    return {**plan, "terrain": rec}, k


def test_a_wall_beside_the_field_is_climbed_over_on_a_spiral(tmp_path, flat_plan):
    """Before (main at ebf59d1) this plan was refused by every export ("a take-off climb from
    the field ... re-plan the first or last leg"). Now: QGC takes off to the field + 150 m,
    orbits the field (NAV_LOITER_TO_ALT, radius v / turn rate) up to the spiral's top and
    flies on; every point of the spiral, and the straight climb on from its top, keep the
    clearance over the recorded ground; KML, GeoJSON and the HTML report draw the spiral."""
    plan, k = _walled(flat_plan)
    write_plan(plan, tmp_path / "plan.json")
    loaded = load_plan(tmp_path / "plan.json")
    t = from_record(loaded["terrain"])
    prof = plan_profiles(loaded)[k]
    sp = prof.climb
    assert sp is not None and all(
        p.climb is None for j, p in enumerate(plan_profiles(loaded)) if j != k
    )
    clear = t.min_clearance_m - 1e-6
    xy, z = sp.points()
    assert np.all(z - t.ground_at(xy) >= clear)  # every point of the orbit, the clearance's ground
    grad = math.tan(t.max_pitch_rad)
    assert sp.radius_m == pytest.approx(loaded["flight"]["transit_speed_mps"] / t.turn_rate_rad_s)
    assert sp.from_m == pytest.approx(VALLEY_M + t.min_clearance_m)
    assert sp.to_m > VALLEY_M + grad * 3e3  # above where the straight climb met the wall
    path = np.asarray(mission_path(loaded["uavs"][k]), dtype=float)[:2]
    d = np.linspace(0.0, np.hypot(*(path[1] - path[0])), 400)
    line = path[0] + (path[1] - path[0]) * (d / d[-1])[:, None]
    after = np.minimum(np.interp(d, _dist(prof.points_m[: int(np.argmax(prof.vertex == 1)) + 1]),
                                 prof.amsl_m[: int(np.argmax(prof.vertex == 1)) + 1]),
                       sp.to_m + grad * d)  # fmt: skip
    ground = bilinear(t.ground_m, t.origin_m, t.cell_m, line)
    assert np.all(after - ground >= clear)  # the straight climb on from the spiral's top

    for fmt in ("qgc", "kml", "geojson", "html"):
        export_plan(tmp_path / "plan.json", fmt, out_dir=tmp_path / fmt)
    uid = plan["uavs"][k]["id"]
    doc = json.loads((tmp_path / "qgc" / f"plan_uav{uid}.plan").read_text())
    assert validate_qgc(doc) == []
    items = doc["mission"]["items"]
    loiter = [it for it in items if it["command"] == MAV_CMD_NAV_LOITER_TO_ALT]
    assert len(loiter) == 1
    assert items[0]["command"] == 22 and items[0]["params"][6] == round(sp.from_m, 1)
    assert loiter[0]["params"][4:6] == items[0]["params"][4:6]  # over the take-off field
    assert loiter[0]["params"][6] == round(sp.to_m, 1)
    assert loiter[0]["params"][1] == round(sp.radius_m, 1)
    other = [p for p in (tmp_path / "qgc").glob("*.plan") if p.name != f"plan_uav{uid}.plan"]
    assert other and all('"command": 31' not in p.read_text() for p in other)
    gj = json.loads(next((tmp_path / "geojson").glob("*.geojson")).read_text())
    (spiral,) = [f for f in gj["features"] if f["properties"]["kind"] == CLIMB_KIND]
    assert spiral["properties"]["id"] == uid
    assert [c[2] for c in spiral["geometry"]["coordinates"]] == [round(float(v), 1) for v in z]
    kml = next((tmp_path / "kml").glob("*.kml")).read_bytes()
    assert validate_kml(kml) == [] and b"climb spiral" in kml
    assert b"climb spiral" in next((tmp_path / "html").glob("*.html")).read_bytes()


def _dist(pts: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))])


def test_a_spiral_beyond_the_endurance_is_refused_naming_the_uav(tmp_path, flat_plan):
    """The spiral's minutes are charged against eq. 18's 0.85 T on top of the plan's flight
    time: a UAV left up to half the spiral's time short is refused by every export, named with the
    minutes missing, nothing written; with the whole spiral's time in hand it exports."""
    plan, k = _walled(flat_plan)
    write_plan(plan, tmp_path / "probe.json")
    sp = plan_profiles(load_plan(tmp_path / "probe.json"))[k].climb
    assert sp is not None
    flight_s = plan["uavs"][k]["flight_time_s"]
    # half the spiral short, or less where another UAV flies longer than that (the others'
    # flights must fit: which UAV flies longest depends on the planner's choices)
    others = max(u["flight_time_s"] for j, u in enumerate(plan["uavs"]) if j != k)
    usable = max(flight_s + sp.time_s / 2, others + 1.0)
    assert usable < flight_s + sp.time_s - 6.0  # at least 0.1 min short
    short = {**plan["terrain"], "usable_endurance_s": usable}
    write_plan({**plan, "terrain": short}, tmp_path / "plan.json")
    uid = plan["uavs"][k]["id"]
    missing = f"{(flight_s + sp.time_s - usable) / 60:.1f} min missing"
    for fmt in ("qgc", "kml", "geojson", "html"):
        with pytest.raises(
            ConfigError, match=rf"plan\.uavs\[{k}\] \(UAV {uid}\).*spiral.*{missing}"
        ):
            export_plan(tmp_path / "plan.json", fmt, out_dir=tmp_path / fmt)
        assert not (tmp_path / fmt).exists()
    enough = {**plan["terrain"], "usable_endurance_s": flight_s + sp.time_s + 1.0}
    write_plan({**plan, "terrain": enough}, tmp_path / "fits.json")
    export_plan(tmp_path / "fits.json", "qgc", out_dir=tmp_path / "fits")
    assert len(list((tmp_path / "fits").glob("*.plan"))) == len(plan["uavs"])


def test_a_mission_whose_climb_clears_exports_as_before(tmp_path, flat_plan):
    """No spiral where the straight climb clears: no NAV_LOITER_TO_ALT, no spiral drawn, and
    the same bytes in every format whether the terrain record carries the turn rate and 0.85 T
    (recorded since) or not (a plan written before)."""
    rec = flat_plan["terrain"]
    assert {"max_turn_rate_deg_s", "usable_endurance_s"} <= set(rec)
    old = {
        key: v for key, v in rec.items() if key not in ("max_turn_rate_deg_s", "usable_endurance_s")
    }
    assert all(p.climb is None for p in plan_profiles(flat_plan))
    for fmt in ("qgc", "kml", "geojson", "html"):
        outs = []
        for name, plan in (("new", flat_plan), ("old", {**flat_plan, "terrain": old})):
            write_plan(plan, tmp_path / "plan.json")  # one path: the exports name it
            export_plan(tmp_path / "plan.json", fmt, out_dir=tmp_path / f"{name}_{fmt}")
            files = sorted((tmp_path / f"{name}_{fmt}").iterdir())
            outs.append([(p.name, p.read_bytes()) for p in files])
        assert outs[0] == outs[1]
        assert all(
            b"climb spiral" not in data and b'"command": 31' not in data for _, data in outs[0]
        )
