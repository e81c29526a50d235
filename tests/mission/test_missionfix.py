"""Missions a planning officer can fly at real climb rates, and the mission leftovers
(i24-missionfix).

The fixture is test_vertical_rates' plan over a flat 600 m valley (an elevation grid in the
scenario), its terrain record given a hill across UAV k's first leg 1.5-2.5 km from the field:
at eq. 19's 15 deg the straight take-off climb clears it; at PX4's 5 m/s it meets it before
the climb spiral's first altitude, so the take-off departs on a heading of its own.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from poc_env.agents.mission import terrain as terrain_mod
from poc_env.agents.mission.crs import to_geographic
from poc_env.agents.mission.export import export_plan
from poc_env.agents.mission.formats.qgc import MAV_CMD_NAV_TAKEOFF
from poc_env.agents.mission.plan import CLIMB_KIND, write_plan
from poc_env.agents.mission.terrain import (
    bilinear,
    departure_heading_deg,
    from_record,
    plan_profiles,
)
from poc_env.agents.planning.geography import fit_orbits
from poc_env.agents.planning.planner import make_plan
from poc_env.agents.testing.terrain import (
    BOWL_KM,
    VALLEY_M,
    hill_across_first_leg,
    valley_to_bowl,
)
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.theory.probability_map import build_prior

PX4 = 5.0  # FW_T_CLMB_MAX, FW_T_SINK_MAX defaults (m/s)


def _valley(ring_m: float | None = None):
    """valley -> bowl over a flat valley, 2 UAVs; with ``ring_m`` a ring of that height 6-8 km
    round bowl (test_orbit_fit's)."""
    return load_scenario(valley_to_bowl(ring_m))


@pytest.fixture(scope="module")
def hill_plan() -> tuple[dict, int]:
    """The flat valley's 2-UAV allocation plan with a 900 m hill (300 m above the field)
    across the longest first leg, 1.5-2.5 km out."""
    plan = make_plan(_valley(), planner="allocation", uavs=2, refine=0)
    legs = [np.hypot(*np.subtract(u["waypoints_m"][0], u["takeoff_m"])) for u in plan["uavs"]]
    k = int(np.argmax(legs))
    rec = hill_across_first_leg(plan, k, 1500.0, 2500.0, 500.0, VALLEY_M + 300.0)
    return {**plan, "terrain": rec}, k


def _rates(plan: dict, climb: float, sink: float) -> dict:
    """``plan`` whose terrain record carries the aircraft's rates."""
    return {**plan, "terrain": {**plan["terrain"], "max_climb_rate_mps": climb,
                                "max_sink_rate_mps": sink}}  # fmt: skip


def test_a_take_off_that_meets_rising_ground_departs_on_a_heading_of_its_own(
    hill_plan, tmp_path, capsys, monkeypatch
):
    """At 5 m/s the take-off climb towards the first waypoint meets the hill before the climb
    spiral's first altitude (refused before: the day audit's probes 13 and 14 at PX4's
    defaults). Now it climbs out on another heading, 15 deg steps from the route's, over level
    ground, to the orbit's first altitude, above the ground all the way; the climb out and
    back is charged; QGC's take-off item stands on that heading, GeoJSON draws it, and the
    export says which heading to launch on (on stderr). At eq. 19 nothing changes."""
    plan, k = hill_plan
    assert plan_profiles(plan, charge=False)[k].climb is None  # type: ignore[index]  # eq. 19
    px4 = _rates(plan, PX4, PX4)
    t = from_record(px4["terrain"])
    p = plan_profiles(px4, charge=False)[k]  # type: ignore[index]
    sp = p.climb
    assert sp is not None and sp.depart_m > 0.0
    u = px4["uavs"][k]
    route = math.atan2(*np.subtract(u["waypoints_m"][0], u["takeoff_m"])[::-1])
    turned = math.remainder(sp.start_rad - route, 2.0 * math.pi)
    assert abs(turned) >= math.radians(15.0) - 1e-9
    assert math.degrees(turned) % 15.0 == pytest.approx(0.0, abs=1e-6) or math.degrees(
        turned
    ) % 15.0 == pytest.approx(15.0, abs=1e-6)
    # the climb out, at the rate-bound gradient from the field, above the ground beyond the
    # field's own cells, reaching the orbit's first altitude
    up = math.tan(terrain_mod.vertical_angle(t, terrain_mod.route_speed_mps(px4["flight"]), True))
    s = np.linspace(0.0, sp.depart_m, 200)
    xy = np.asarray(sp.center_m) + s[:, None] * [math.cos(sp.start_rad), math.sin(sp.start_rad)]
    far = s > 1.5 * t.cell_m * math.sqrt(2.0)
    alt = p.field_m + up * s
    assert np.all(alt[far] > bilinear(t.ground_m, t.origin_m, t.cell_m, xy[far]))
    assert alt[-1] == pytest.approx(sp.from_m)
    assert sp.time_s == pytest.approx((sp.length_m + 2.0 * sp.depart_m) / sp.speed_mps)
    # without the departure, the mission is refused naming the take-off (as on main)
    with monkeypatch.context() as m:
        m.setattr(terrain_mod, "departure_spiral", lambda *a, **kw: None)
        with pytest.raises(ConfigError, match="take-off climb"):
            plan_profiles(px4, charge=False)
    # the exports: QGC's take-off item on the heading, GeoJSON's spiral with its departure
    write_plan(px4, tmp_path / "plan.json")
    export_plan(tmp_path / "plan.json", "qgc", out_dir=tmp_path / "q")
    said = capsys.readouterr()
    assert f"plan.uavs[{k}] (UAV {u['id']}): its take-off climbs out on heading" in said.err
    assert "warning" not in said.out
    doc = json.loads((tmp_path / "q" / f"plan_uav{u['id']}.plan").read_text())
    take = next(it for it in doc["mission"]["items"] if it["command"] == MAV_CMD_NAV_TAKEOFF)
    lat, lon = to_geographic([list(sp.depart_xy)], px4["crs"])[0]
    assert take["params"][4:7] == pytest.approx([lat, lon, round(sp.from_m, 1)], abs=1e-6)
    export_plan(tmp_path / "plan.json", "geojson", out_dir=tmp_path / "g")
    gj = json.loads(next((tmp_path / "g").glob("*.geojson")).read_text())
    (line,) = [f for f in gj["features"] if f["properties"]["kind"] == CLIMB_KIND]
    assert line["properties"]["departure_heading_deg"] == pytest.approx(
        departure_heading_deg(sp), abs=0.05
    )
    lon0, lat0, z0 = line["geometry"]["coordinates"][0]
    home = to_geographic([list(sp.center_m)], px4["crs"])[0]
    assert (lat0, lon0) == pytest.approx(home, abs=1e-6) and z0 == pytest.approx(p.field_m)


def test_fit_orbits_reads_the_terrain_record_once(monkeypatch):
    """Leftover c: the orbit fit's trials (one per dropped waypoint, then the bisection) each
    read the whole terrain grid from the plan's record again; now once, the same plan out.
    The plan is test_orbit_fit's ring: planned in 2-D (the flat valley's routes), its descent
    orbits do not fit until the routes are cut."""
    sc = _valley(VALLEY_M + 2500.0)
    ring = make_plan(sc, planner="allocation", uavs=2, refine=0)
    flat = make_plan(_valley(), planner="allocation", uavs=2, refine=0)
    assert ring.get("orbit_fit")  # the fit cut the ring's routes
    reads = []
    real = terrain_mod.from_record

    def counted(rec):
        reads.append(1)
        return real(rec)

    monkeypatch.setattr(terrain_mod, "from_record", counted)
    uncut = {**flat, "terrain": ring["terrain"]}  # the routes before the fit, the ring's ground
    fitted = fit_orbits(uncut, sc, build_prior(sc.map))
    assert len(reads) == 1
    assert fitted["uavs"] == ring["uavs"] and fitted["orbit_fit"] == ring["orbit_fit"]


def test_tracks_read_from_an_export_glide_from_the_descent_orbit_exit(tmp_path):
    """Leftover d: over a ring round the landing field the UAVs land on a descent orbit. The
    route line GeoJSON and KML draw (and ``replan --tracks`` reads as flown) ran straight from
    the approach point (the orbit's centre) to the field, where the aircraft flew the orbit
    and then glided from its tangent exit; now the route's last leg is that glide."""
    from poc_env.agents.planning.replan import read_tracks
    from poc_env.agents.testing.terrain import ring_around

    plan = make_plan(_valley(), planner="allocation", uavs=2, refine=0)
    plan = ring_around(plan, BOWL_KM, 6.0, 8.0, VALLEY_M + 1500.0)
    write_plan(plan, tmp_path / "plan.json")
    profs = plan_profiles(plan)
    assert profs is not None
    landing = [(u, p) for u, p in zip(plan["uavs"], profs) if p.descent is not None]
    assert landing
    for fmt, suffix in (("geojson", "*.geojson"), ("kml", "*.kml")):
        export_plan(tmp_path / "plan.json", fmt, out_dir=tmp_path / fmt)
        tracks = read_tracks(next((tmp_path / fmt).glob(suffix)), plan["crs"])
        for u, p in landing:
            d = p.descent
            assert d is not None
            (route,) = [  # the UAV's route: through its approach point, to the field
                pts for _, pts in tracks
                if len(pts) > 3 and np.allclose(pts[-1], u["landing_m"], atol=1.0)
                and np.min(np.hypot(*(pts - np.asarray(d.orbit.center_m)).T)) < 1.0
            ]  # fmt: skip
            assert np.allclose(route[-3], d.orbit.center_m, atol=1.0), fmt
            assert np.allclose(route[-2], d.exit_m, atol=1.0), fmt  # then the glide flown


def test_a_trimmed_de_plan_keeps_no_stale_rectangle_x_or_objective():
    """Leftover e: a DE plan trimmed for its orbits kept each trimmed UAV's decision rectangle
    and flown strip (drawn as its search by every export, though its last lines are no longer
    flown) and the optimiser's ``x`` and ``objective`` of the untrimmed routes. Now the
    trimmed UAV's search is the areas its kept lines sweep, and the untrimmed decision is
    recorded in ``orbit_fit`` only. (The DE-like plan: test_orbit_fit's ring routes with a
    DE plan's rectangle fields; a real DE plan there takes 20 s of CPU.)"""
    from poc_env.agents.mission.plan import check_plan, search_rings

    sc = _valley(VALLEY_M + 2500.0)
    ring = make_plan(sc, planner="allocation", uavs=2, refine=0)
    flat = make_plan(_valley(), planner="allocation", uavs=2, refine=0)
    rect = {"center_m": [20e3, 20e3], "length_m": 10e3, "width_m": 5e3, "theta_deg": 0.0}
    strip = {"center_m": [20e3, 20e3], "line_length_m": 9e3, "strip_width_m": 5e3,
             "lines_theta_rad": 0.0, "rule": "lines"}  # fmt: skip
    uavs = [{**{k: v for k, v in u.items() if k not in ("areas_m", "transit_waypoints")},
             "rectangle": rect, "flown_rectangle": strip} for u in flat["uavs"]]  # fmt: skip
    de = {**{k: v for k, v in flat.items() if k != "speeds_mps"}, "uavs": uavs,
          "terrain": ring["terrain"], "x": [0.5] * 10, "objective": -flat["posc"]}  # fmt: skip
    fitted = fit_orbits(de, sc, build_prior(sc.map))
    fit = fitted["orbit_fit"]
    assert fit["uavs"]  # trimmed
    assert "x" not in fitted and "objective" not in fitted
    assert fit["x_before"] == de["x"] and fit["objective_before"] == de["objective"]
    for u in fitted["uavs"]:
        if str(u["id"]) in fit["uavs"]:
            assert u["rectangle"] is None and u["flown_rectangle"] is None
            assert fit["uavs"][str(u["id"])]["rectangle_before"] == rect
            assert u["areas_m"] and {k for k, _, _ in search_rings(u)} == {"search_area"}
        else:
            assert u["rectangle"] == rect
    check_plan(fitted)


def test_survey_plan_out_leaves_time_for_the_descent_orbit(tmp_path):
    """Leftover f: ``survey --plan-out`` wrote no plan when a UAV's pattern fitted 0.85 T
    alone but not with its descent orbit (refused: "... min missing for the orbits"), where
    ``plan`` trims the route (``fit_orbits``). Now the survey's plan is trimmed the same way
    and exported. The endurance is set so that 0.85 T lies between the pattern's flight
    (90.2 min) and flight + orbit (94.9 min)."""
    import yaml

    from poc_env.agents.mission.plan import load_plan
    from poc_env.cli import main

    sc = valley_to_bowl(VALLEY_M + 2500.0, count=1)
    sc["uav"] = {**sc["uav"], "endurance_h": 1.79}
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(sc))
    regs = [{"id": 1, "kind": "polygon", "spacing_km": 5.0, "direction_deg": 90.0,
             "vertices_km": [[0, 0], [20, 0], [20, 40], [0, 40]]}]  # fmt: skip
    (tmp_path / "r.yaml").write_text(
        yaml.safe_dump({"name": "strips", "scenario": "alps", "regions": regs})
    )
    out = tmp_path / "p.json"
    argv = ["survey", "--scenario", str(tmp_path / "s.yaml"), "--regions",
            str(tmp_path / "r.yaml"), "--plan-out", str(out)]  # fmt: skip
    assert main(argv) == 0
    plan = load_plan(out)
    assert plan["orbit_fit"]["uavs"]["1"]["waypoints_after"] >= 1
    usable = 0.85 * 1.79 * 3600.0
    (u,) = plan["uavs"]
    (p,) = plan_profiles(plan)  # type: ignore[misc]
    assert p.descent is not None
    assert u["flight_time_s"] + terrain_mod.orbit_time_s(p) <= usable + 1e-6
    assert main(["export", str(out), "--format", "qgc", "--out", str(tmp_path / "q")]) == 0


def test_field_mates_on_one_approach_are_given_approaches_apart(tmp_path):
    """Leftover g: the altitude layers stop at the landing approach (one glide slope per field:
    two UAVs on one glide path are at one altitude over each point, whatever their layers), so
    field-mates whose approach points coincided (the day audit's swall2 and s150land: 0.11
    km apart) could meet on the approach. With layers, the later UAV's approach is now turned
    round the field to the nearest side at least APPROACH_APART_M from its mate's; without
    layers nothing changes."""
    from poc_env.agents.mission.features import with_layers
    from poc_env.agents.mission.formats.qgc import MAV_CMD_DO_LAND_START
    from poc_env.agents.mission.plan import APPROACH_APART_M, approach_point

    plan = make_plan(_valley(), planner="allocation", uavs=2, refine=0)
    first = plan["uavs"][0]
    bowl = [float(v) * 1e3 for v in BOWL_KM]
    plan["uavs"] = [{**u, "landing_m": bowl, "waypoints_m": first["waypoints_m"],
                     "flight_time_s": first["flight_time_s"]} for u in plan["uavs"]]  # fmt: skip
    same = [approach_point(u) for u in plan["uavs"]]
    assert np.allclose(same[0], same[1])  # one approach for both, as planned
    assert with_layers(plan, 0.0) is plan
    lay = with_layers(plan, 30.0)
    apps = [approach_point(u) for u in lay["uavs"]]
    assert np.allclose(apps[0], same[0])  # the first keeps its side
    assert math.dist(apps[0], apps[1]) >= APPROACH_APART_M - 1e-6
    assert math.dist(apps[1], bowl) == pytest.approx(4000.0)  # 4 km out, another side
    write_plan(plan, tmp_path / "plan.json")
    export_plan(tmp_path / "plan.json", "qgc", out_dir=tmp_path / "q", separation_m=30.0)
    at = []
    for u in plan["uavs"]:
        items = json.loads((tmp_path / "q" / f"plan_uav{u['id']}.plan").read_text())["mission"][
            "items"
        ]
        i = [it["command"] for it in items].index(MAV_CMD_DO_LAND_START)
        at.append(items[i + 1]["params"][4:6])  # the approach waypoint (lat, lon)
    want = to_geographic(apps, plan["crs"])
    assert np.allclose(at, want, atol=1e-6)
