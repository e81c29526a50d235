"""The aircraft's vertical rates bound every altitude change of a mission over terrain
(i24-rates): ``uav.max_climb_rate_mps`` / ``uav.max_sink_rate_mps`` (PX4's FW_T_CLMB_MAX /
FW_T_SINK_MAX) make eq. 19's per-metre bound ``min(tan(beta_max), rate / v)``
(:func:`~poc_env.agents.mission.terrain.vertical_angle`) for the profile, the take-off climb
and its spiral, the final glide and the descent orbit, and their charged minutes; unset, an
export says which missions need more than the autopilots' default 5 m/s.

The fixtures are test_climb_spiral's and test_final_glide's plans over a flat 600 m valley
(an elevation grid in the scenario), their terrain records given high ground.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from poc_env.agents.mission.export import export_plan
from poc_env.agents.mission.features import with_layers
from poc_env.agents.mission.plan import check_plan, flight, write_plan
from poc_env.agents.mission.terrain import (
    bilinear,
    from_record,
    orbit_time_s,
    plan_profiles,
    route_speed_mps,
    tangent_exit,
    vertical_rates,
)
from poc_env.agents.planning.planner import make_plan
from poc_env.agents.testing.terrain import (
    BOWL_KM,
    VALLEY_KM,
    VALLEY_M,
    hill_across_first_leg,
    ring_around,
    valley_to_bowl,
)
from poc_env.config import load_scenario
from poc_env.errors import ConfigError

PX4 = 5.0  # FW_T_CLMB_MAX, FW_T_SINK_MAX defaults (m/s)


def _valley(ring_m: float | None = None, **uav: float):
    """valley -> bowl over a flat valley, 2 UAVs; with ``ring_m`` a ring of that height 6-8 km
    round bowl (test_orbit_fit's); ``uav`` overrides the UAV's fields."""
    sc = load_scenario(valley_to_bowl(ring_m))
    return load_scenario(sc, {f"uav.{k}": v for k, v in uav.items()}) if uav else sc


@pytest.fixture(scope="module")
def flat_plan() -> dict:
    """A 2-UAV allocation plan over the flat valley (no rates: eq. 19 alone)."""
    return make_plan(_valley(), planner="allocation", uavs=2, refine=0)


def _with_rates(plan: dict, climb: float | None = None, sink: float | None = None) -> dict:
    """``plan`` whose terrain record carries the aircraft's rates (as a scenario with
    ``uav.max_climb_rate_mps`` / ``max_sink_rate_mps`` records them)."""
    rec = {k: v for k, v in plan["terrain"].items() if k not in ("max_climb_rate_mps",
                                                                  "max_sink_rate_mps")}  # fmt: skip
    if climb is not None:
        rec["max_climb_rate_mps"] = climb
    if sink is not None:
        rec["max_sink_rate_mps"] = sink
    return {**plan, "terrain": rec}


def _hill(plan: dict, height_m: float, from_m: float = 3e3) -> tuple[dict, int]:
    """``plan`` with a hill ``height_m`` across the longest first leg, from ``from_m`` to 1 km
    farther from the field."""
    legs = [np.hypot(*np.subtract(u["waypoints_m"][0], u["takeoff_m"])) for u in plan["uavs"]]
    k = int(np.argmax(legs))
    rec = hill_across_first_leg(plan, k, from_m, from_m + 1e3, 500.0, height_m)
    return {**plan, "terrain": rec}, k


def _rates(plan: dict, k: int) -> dict:
    """{(phase, kind): rate} of UAV ``k``'s mission (the fastest of each)."""
    t = from_record(plan["terrain"])
    fl = flight(plan)
    p = plan_profiles(plan, charge=False)[k]  # type: ignore[index]
    rates = vertical_rates(t, p, fl["transit_speed_mps"], route_speed_mps(fl))
    return {(phase, kind): r for phase, kind, r, _ in rates}


def test_a_climb_beyond_the_rate_is_flown_on_a_spiral_that_clears(flat_plan):
    """A 1,200 m hill 3-4 km out: eq. 19's straight climb (15 deg, 16.4 m/s at 220 km/h)
    clears it; at 5 m/s (4.7 deg) it would meet it, so the UAV climbs on a spiral over its
    field first, climbing at 5 m/s (more turns, its minutes charged), and every point of the
    spiral, and of the route (within 5 m/s on every leg), keeps the clearance."""
    plan, k = _hill(flat_plan, 1200.0)
    before = plan_profiles(plan, charge=False)[k]  # type: ignore[index]
    assert before.climb is None  # eq. 19 clears the hill straight
    assert _rates(plan, k)[("straight take-off climb", "climb")] > PX4  # and needs more than 5
    limited = _with_rates(plan, climb=PX4, sink=PX4)
    t = from_record(limited["terrain"])
    p = plan_profiles(limited, charge=False)[k]  # type: ignore[index]
    sp = p.climb
    assert sp is not None
    assert math.tan(sp.pitch_rad) * sp.speed_mps == pytest.approx(PX4)  # climbs at the rate
    assert sp.time_s == pytest.approx((sp.to_m - sp.from_m) / PX4)
    xy, z = sp.points()
    assert np.all(z - t.ground_at(xy) >= t.min_clearance_m - 1e-6)
    assert np.all(p.amsl_m - p.ground_m >= t.min_clearance_m - 1e-6)
    rates = _rates(limited, k)
    assert rates[("route legs", "climb")] <= PX4 + 1e-6
    assert rates[("route legs", "sink")] <= PX4 + 1e-6
    # the straight climb on from the spiral's top, at the rate, stays above the ground
    v = route_speed_mps(flight(limited))
    dist = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(p.points_m, axis=0).T))])
    climb = np.minimum(p.amsl_m, sp.to_m + PX4 / v * dist)
    ground = bilinear(t.ground_m, t.origin_m, t.cell_m, p.points_m)
    assert np.all(climb > ground)


def test_a_higher_hill_gets_a_longer_spiral_at_the_rate(flat_plan):
    """A 2,500 m hill 5-6 km out: eq. 19 already spirals (600 m + tan 15 deg x 5 km = 1,940 m);
    at 5 m/s the spiral climbs at least as high and takes longer (charged): (top - start) / 5
    seconds, more turns."""
    plan, k = _hill(flat_plan, 2500.0, 5e3)
    eq19 = plan_profiles(plan, charge=False)[k].climb  # type: ignore[index]
    px4 = plan_profiles(_with_rates(plan, climb=PX4), charge=False)[k].climb  # type: ignore[index]
    assert eq19 is not None and px4 is not None
    assert px4.to_m >= eq19.to_m - 1e-6
    assert px4.time_s == pytest.approx((px4.to_m - px4.from_m) / PX4)
    assert px4.time_s > eq19.time_s * 2  # 16.4 m/s vs 5 m/s
    assert px4.turns > eq19.turns


def test_a_descent_orbit_is_charged_longer_as_the_sink_rate_falls(flat_plan):
    """test_final_glide's ring round bowl: the descent orbit's charged minutes grow as
    ``max_sink_rate_mps`` falls (eq. 19's 16.4 m/s, then 10, 5, 2 m/s), each descending at
    that rate."""
    plan = ring_around(flat_plan, BOWL_KM, 6.0, 8.0, VALLEY_M + 1500.0)
    k = next(i for i, p in enumerate(plan_profiles(plan, charge=False)) if p.descent)  # type: ignore[union-attr, arg-type]
    times = []
    for sink in (None, 10.0, PX4, 2.0):
        p = plan_profiles(_with_rates(plan, sink=sink), charge=False)[k]  # type: ignore[index]
        o = p.descent.orbit
        rate = math.tan(o.pitch_rad) * o.speed_mps
        assert rate == pytest.approx(sink) if sink else rate > 10.0
        times.append(orbit_time_s(p))
    assert times == sorted(times) and len(set(times)) == 4


def test_orbit_fit_trims_a_plan_that_fits_at_eq19_but_not_at_the_rate():
    """test_orbit_fit's 3,100 m ring round bowl: the plan at eq. 19 fits flight + orbits in
    0.85 T; at a 2 m/s sink its descent orbits take longer, so the plan made for that aircraft
    trims its routes further, and each UAV's flight + orbits (at 2 m/s) fits."""
    ring = VALLEY_M + 2500.0
    eq19 = make_plan(_valley(ring), planner="allocation", uavs=2, refine=0)
    sc = _valley(ring, max_sink_rate_mps=2.0)
    slow = make_plan(sc, planner="allocation", uavs=2, refine=0)
    assert slow["terrain"]["max_sink_rate_mps"] == 2.0
    usable = sc.uav.usable_endurance_s
    at_rate = plan_profiles(_with_rates(eq19, sink=2.0), charge=False)
    assert any(  # eq. 19's plan does not fit at the rate
        u["flight_time_s"] + orbit_time_s(p) > usable + 1e-6
        for u, p in zip(eq19["uavs"], at_rate)  # type: ignore[arg-type]
    )
    for u, p in zip(slow["uavs"], plan_profiles(slow, charge=False)):  # type: ignore[arg-type]
        assert u["flight_time_s"] + orbit_time_s(p) <= usable + 1e-6
    assert sum(u["flight_time_s"] for u in slow["uavs"]) < sum(
        u["flight_time_s"] for u in eq19["uavs"]
    )


@pytest.mark.parametrize("value", [-1, 0, "fast", True, float("nan"), 1000])
@pytest.mark.parametrize("key", ["max_climb_rate_mps", "max_sink_rate_mps"])
def test_bad_rates_are_refused_naming_the_field(key, value, flat_plan):
    """Negative, zero, non-number, NaN or beyond 100 m/s: refused by the scenario (naming
    ``uav.<key>``, the value and the range) and in a plan's terrain record."""
    with pytest.raises(ConfigError) as err:
        load_scenario("small", {f"uav.{key}": value})
    assert f"uav.{key}" in str(err.value) and "(0, 100]" in str(err.value)
    assert repr(value) in str(err.value) or str(value) in str(err.value)
    bad = {**flat_plan, "terrain": {**flat_plan["terrain"], key: value}}
    with pytest.raises(ConfigError, match=rf"plan\.terrain\.{key}"):
        check_plan(bad)


def test_rates_are_recorded_only_when_given(flat_plan):
    """A scenario without rates records none (plans and exports byte-identical to before);
    with them the plan's terrain record carries them."""
    assert "max_climb_rate_mps" not in flat_plan["terrain"]
    assert "max_sink_rate_mps" not in flat_plan["terrain"]
    sc = _valley(max_climb_rate_mps=4.5, max_sink_rate_mps=6.0)
    rec = make_plan(sc, planner="allocation", uavs=2, refine=0)["terrain"]
    assert (rec["max_climb_rate_mps"], rec["max_sink_rate_mps"]) == (4.5, 6.0)


def test_export_names_the_missions_that_need_more_than_5_m_s(tmp_path, capsys, flat_plan):
    """Unset rates: the export prints, per UAV whose mission needs more than 5 m/s, the phase
    and the rate, and how to set them; the files are those written without the warning. Set,
    no warning."""
    plan, k = _hill(flat_plan, 1200.0)
    write_plan(plan, tmp_path / "plan.json")
    export_plan(tmp_path / "plan.json", "geojson", out_dir=tmp_path / "a")
    out = capsys.readouterr().err
    u = plan["uavs"][k]
    line = next(s for s in out.splitlines() if f"plan.uavs[{k}] (UAV {u['id']})" in s)
    rate = _rates(plan, k)[("straight take-off climb", "climb")]
    assert f"climb {rate:.1f} m/s on its straight take-off climb" in line
    assert "uav.max_climb_rate_mps" in out and "FW_T_CLMB_MAX" in out
    write_plan(_with_rates(plan, climb=30.0, sink=30.0), tmp_path / "fast.json")
    export_plan(tmp_path / "fast.json", "geojson", out_dir=tmp_path / "b")
    assert "FW_T_CLMB_MAX" not in capsys.readouterr().err


def _mates(plan: dict, same_route: bool = False) -> dict:
    """``plan`` with both UAVs taking off at ``valley`` and landing at ``bowl`` (field-mates);
    with ``same_route`` the second flies the first's route (one approach point: concentric
    descent orbits)."""
    start = [float(v) * 1e3 for v in VALLEY_KM]
    bowl = [float(v) * 1e3 for v in BOWL_KM]
    first = plan["uavs"][0]
    uavs = [
        {**u, "takeoff_m": start, "landing_m": bowl,
         **({"waypoints_m": first["waypoints_m"], "flight_time_s": first["flight_time_s"]}
            if same_route else {})}
        for u in plan["uavs"]
    ]  # fmt: skip
    return {**plan, "uavs": uavs}


def _crossing(inner, outer, target) -> tuple[float, float]:
    """(the run from the inner orbit's tangent exit towards ``target`` to the outer circle,
    the angle round the centre where it crosses it)."""
    c = np.asarray(inner.center_m)
    ex, _ = tangent_exit(c, inner.radius_m, target)
    run = math.sqrt(outer.radius_m**2 - inner.radius_m**2)
    x = ex + (np.asarray(target) - ex) / np.hypot(*(np.asarray(target) - ex)) * run
    return run, math.atan2(x[1] - c[1], x[0] - c[0])


def test_field_mates_climb_spirals_cross_a_layer_apart(tmp_path, flat_plan):
    """test_final_glide's field-mates (a 1,800 m ring 2.5-4.5 km round ``valley``), exported
    with ``separation_m`` 30: UAV 2's spiral is 30 m wider; UAV 1, leaving the inner one
    towards its first waypoint, crosses UAV 2's circle. Before (measured on probe 13) it left
    at its own top, within UAV 2's altitudes there. Now it tops out 30 m above UAV 2's top plus
    what it may descend over the run to the crossing: at the crossing it is at least 30 m
    above every altitude UAV 2 flies on its circle; the QGC loiter carries that top."""
    plan = _mates(ring_around(flat_plan, VALLEY_KM, 2.5, 4.5, VALLEY_M + 1200.0))
    sep = 30.0
    layered = with_layers(plan, sep)
    t = from_record(plan["terrain"])
    profs = plan_profiles(layered, charge=False)
    alone = plan_profiles(plan, charge=False)
    assert profs is not None and alone is not None
    inner, outer = (p.climb for p in profs)
    assert inner is not None and outer is not None
    assert outer.radius_m == pytest.approx(inner.radius_m + sep)
    down = math.tan(t.max_pitch_rad)  # no rates: eq. 19's
    run, _ = _crossing(inner, outer, layered["uavs"][0]["waypoints_m"][0])
    lowest = inner.to_m - down * run  # the inner UAV at the crossing, at worst
    assert lowest >= outer.to_m + sep - 1e-6  # above the outer's every altitude (its top)
    assert alone[0].climb.to_m < outer.to_m + sep  # type: ignore[union-attr]  # was not
    assert profs[1].climb == outer  # the outer orbit unchanged (nothing outside it)
    write_plan(plan, tmp_path / "plan.json")
    export_plan(tmp_path / "plan.json", "qgc", out_dir=tmp_path / "q", separation_m=sep)
    uid = plan["uavs"][0]["id"]
    doc = json.loads((tmp_path / "q" / f"plan_uav{uid}.plan").read_text())
    (loiter,) = [it for it in doc["mission"]["items"] if it["command"] == 31]
    assert loiter["params"][6] == round(inner.to_m, 1)


def test_field_mates_descent_orbits_cross_a_layer_apart(flat_plan):
    """Both UAVs fly one route to ``bowl`` over the 2,100 m ring (one approach point: two
    concentric descent orbits with ``separation_m`` 30). The inner UAV's glide from its exit
    crosses the outer circle; the outer orbit now ends 30 m above that crossing, so the outer
    UAV flies above it at every pass (its glide steeper by that, within eq. 19)."""
    plan = _mates(ring_around(flat_plan, BOWL_KM, 6.0, 8.0, VALLEY_M + 1500.0), same_route=True)
    sep = 30.0
    lay = with_layers(plan, sep)
    # with_layers turns the second UAV's approach 15 deg round the field (i24-missionfix:
    # field-mates' approaches kept apart); one approach point remains where no other side is
    # free (zones, the glide), as here by hand
    lay["uavs"][1].pop("approach_m")
    profs = plan_profiles(lay, charge=False)
    alone = plan_profiles(plan, charge=False)
    assert profs is not None and alone is not None
    inner, outer = (p.descent for p in profs)
    assert inner is not None and outer is not None
    assert outer.orbit.radius_m == pytest.approx(inner.orbit.radius_m + sep)
    field = profs[0].landing_field_m
    run, _ = _crossing(inner.orbit, outer.orbit, np.asarray(BOWL_KM) * 1e3)
    cross = inner.orbit.to_m - (inner.orbit.to_m - field) / inner.glide_m * run
    assert outer.orbit.to_m >= cross + sep - 1e-6  # its lowest altitude, above the crossing
    assert alone[1].descent.orbit.to_m < cross + sep  # type: ignore[union-attr]  # was not
    assert (outer.orbit.to_m - field) / outer.glide_m <= math.tan(math.radians(15.0))


def test_the_vertical_rate_limit_is_the_limits_modules_for_scenario_and_plan(flat_plan):
    """i24-leftovers, item 4: the largest vertical rate is ``limits.MAX_VERTICAL_RATE_MPS``,
    beside the other physical ranges (docs/inputs.md), and both the scenario's fields and a
    plan's terrain record take it and refuse the next float above it."""
    from poc_env import limits

    top = limits.MAX_VERTICAL_RATE_MPS
    above = math.nextafter(top, math.inf)
    for key in ("max_climb_rate_mps", "max_sink_rate_mps"):
        assert getattr(load_scenario("small", {f"uav.{key}": top}).uav, key) == top
        check_plan({**flat_plan, "terrain": {**flat_plan["terrain"], key: top}})
        with pytest.raises(ConfigError, match=rf"uav\.{key}"):
            load_scenario("small", {f"uav.{key}": above})
        with pytest.raises(ConfigError, match=rf"plan\.terrain\.{key}"):
            check_plan({**flat_plan, "terrain": {**flat_plan["terrain"], key: above}})
