"""i24-fleet: more UAVs never plan worse, and no UAV idles while reachable mass remains.

The case (:func:`mini`) is the scale audit's big scenario (results/audit/scale/raw/
make_inputs.py: four airfields outside the sides, three zones, twelve weighted sightings)
built without the import, shrunk to 40 x 40 cells."""

import dataclasses
import re

import numpy as np
import pytest

from poc_env.agents.planning.allocation import (
    FILL_WITHIN,
    make_allocation_plan,
    plan_fleets,
    sampled_sweep,
    violation_penalty,
)
from poc_env.agents.planning.deconflict import apart, conflicts, planned_positions
from poc_env.agents.planning.flight_rules import SPEED, plan_speeds
from poc_env.agents.planning.greedy_rectangles import make_greedy_rectangles_plan
from poc_env.agents.planning.options import PlanOptions
from poc_env.agents.planning.relax_patches import out_and_back
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.sim.routing import ZoneRouter
from poc_env.theory.probability_map import Grid


def mini(side_km: float, cell_km: float, n: int, endurance_h: float = 3.0):
    """The audit's big scenario on a ``side_km`` square of ``cell_km`` cells: ``large_400``'s
    UAV (``endurance_h``), airfields North, South, West, East 15 km outside the sides, its
    three zones and twelve sightings (seed 7) at the same relative places; ``n`` UAVs
    round-robin. Returns the scenario and the prior."""
    s = side_km
    fields = {"North": (s / 2, s + 15), "South": (s / 2, -15), "West": (-15, s / 2),
              "East": (s + 15, s / 2)}  # fmt: skip
    boxes = [(0.2, 0.3, 0.35, 0.45), (0.6, 0.55, 0.7, 0.62), (0.45, 0.8, 0.55, 0.9)]
    zones = [[[a * s, b * s], [c * s, b * s], [c * s, d * s], [a * s, d * s]]
             for a, b, c, d in boxes]  # fmt: skip
    sc = load_scenario("large_400", {
        "map.width_km": s, "map.height_km": s, "map.cell_km": cell_km,
        "map.no_fly_zones_km": zones, "uav.endurance_h": endurance_h,
        "airfields": [{"name": k, "position_km": list(v)} for k, v in fields.items()],
        "fleet": [{"takeoff": "North", "count": 1}],
    }).with_uavs(n)  # fmt: skip
    rng = np.random.default_rng(7)
    pts = rng.uniform(0.05 * s, 0.95 * s, (12, 2))
    w = rng.uniform(0.2, 1, 12)
    prior = np.zeros(Grid.from_config(sc.map).shape)
    for (x, y), m in zip(pts, w, strict=True):
        prior[int(y // cell_km), int(x // cell_km)] += m
    return sc, prior / prior.sum()


def reachable_unfound(sc, prior, plan) -> float:
    """The mass the plan leaves that a UAV could reach: per cell the prior's share a sensor
    of lateral range W/2 reaches from outside the zones, where some UAV's straight out and
    back fits 0.85 T, less what the plan finds there (floored at 0)."""
    g = Grid.from_config(sc.map)
    share = ZoneRouter.for_scenario(sc).reach_share(g, reach_m=0.5 * sc.sensor.sweep_width_m)
    to = np.asarray(sc.takeoff_m, float).reshape(-1, 2)
    la = np.asarray(sc.landing_m, float).reshape(-1, 2)
    near = (out_and_back(g, to, la, plan_speeds(sc, SPEED)) < sc.uav.usable_endurance_s).any(0)
    paths = [[to[k], *u["waypoints_m"], la[k]] if u["waypoints_m"] else []
             for k, u in enumerate(plan["uavs"])]  # fmt: skip
    found = sum(sampled_sweep(sc, g, prior, paths)[1], np.zeros(g.shape))
    return float(np.maximum(prior * share * near - found, 0.0).sum())


def test_no_uav_idles_while_reachable_mass_remains():
    """The allocation start alone (its route cut among the fleet) leaves 4 of 8 UAVs without
    a route and 0.014 of the prior reachable but unfound on this case (i24-fleet, measured
    with ``fill_idle=False``); with the fill the idle UAVs fly and nothing reachable is left
    (the inverse-cube sensor's tail finds more than the W/2 model counts: below 1e-3). A
    filled UAV whose route adds less than ``NOTHING`` of the mass stays home (i24-smallfix,
    F1: UAV 8 flew 2.09 h for 2e-7 here), so fewer stay idle than without the fill, not none."""
    sc, prior = mini(200, 5, 8)
    opt = PlanOptions(greedy_start=False, box_start=False, refine=0)
    plan = make_allocation_plan(sc, prior=prior, options=opt)
    plain = make_allocation_plan(sc, prior=prior, options=dataclasses.replace(opt, fill_idle=False))
    idle = sum(not u["waypoints_m"] for u in plan["uavs"])
    assert idle < sum(not u["waypoints_m"] for u in plain["uavs"])
    assert reachable_unfound(sc, prior, plan) < 1e-3


def test_fill_apart_drops_filled_routes_that_break_eq_21():
    """``fill_apart``: a filled route in planned conflict (eq. 21, the deconfliction's
    measure) with a UAV already flying is dropped. On this case the 12 UAVs the allocation
    start leaves idle, filled, are in 11 conflict steps with the others; apart, in none (the
    drop alone left 5 idle; i24-stagger fills them again, the test below)."""
    sc, prior = mini(200, 5, 16)
    base = {"greedy_start": False, "box_start": False, "refine": 0}
    plain = make_allocation_plan(sc, prior=prior, options=PlanOptions(fill_idle=False, **base))
    idle = [k for k, u in enumerate(plain["uavs"]) if not u["waypoints_m"]]
    plan = make_allocation_plan(sc, prior=prior, options=PlanOptions(fill_apart=True, **base))
    assert any(plan["uavs"][k]["waypoints_m"] for k in idle)
    _, pos, act = planned_positions(
        sc, [u["waypoints_m"] for u in plan["uavs"]], plan_speeds(sc, SPEED)
    )
    assert not conflicts(sc, pos, act)[:, idle].any()


def test_fill_apart_refills_a_dropped_uav_instead_of_leaving_it_idle():
    """i24-stagger: on the case above, dropping the filled routes in conflict left 5 of the 12
    filled UAVs idle (two in conflict on the way out with a busy field-mate's bearing, the
    others in their boxes). The fill now fans its routes out clear of the bearings the busy
    field-mates fly and fills a dropped UAV again on the mass left with the mass near its
    conflicts taken out: every UAV flies, and the whole plan keeps eq. 21 away from the
    fields at its planned times. (``nothing=0``: the fill alone; i24-smallfix's rule sends home
    the UAVs whose filled routes add less than ``nothing`` of the mass, tested on its own.)"""
    sc, prior = mini(200, 5, 16)
    opt = PlanOptions(greedy_start=False, box_start=False, refine=0, nothing=0.0)
    plan = make_allocation_plan(sc, prior=prior, options=opt)
    assert all(u["waypoints_m"] for u in plan["uavs"])
    routes = [u["waypoints_m"] for u in plan["uavs"]]
    _, pos, act = planned_positions(sc, routes, plan_speeds(sc, SPEED))
    assert not conflicts(sc, pos, act).any()


def test_apart_keeps_an_alternative_and_drops_what_has_none():
    """``apart``: a route on top of a fixed UAV's route is replaced by the first alternative
    that keeps eq. 21, and dropped (its conflicting positions returned) when none does."""
    sc, _ = mini(200, 5, 8)  # UAVs 0 and 1 share the North field
    v = plan_speeds(sc, SPEED)
    box = [[60e3, 150e3], [140e3, 150e3], [140e3, 145e3], [60e3, 145e3]]
    far = [[150e3, 60e3], [190e3, 60e3], [190e3, 55e3], [150e3, 55e3]]
    routes = [box, box] + [[]] * 6
    out, where = apart(sc, routes, v, [1], lambda k, q: [box, far])
    assert out[0] == box and out[1] == far and not where
    out, where = apart(sc, routes, v, [1])
    assert out[0] == box and out[1] == [] and len(where[1])


def test_pos_c_never_falls_as_the_fleet_grows():
    """plan_fleets: each fleet size planned with the plan of the one before as its floor.
    Without it the default plan falls from 0.9182 (12 UAVs) to 0.9164 (16) on this case
    (another start wins at 16); with it the 16-UAV plan keeps the 12 UAVs' routes and fills
    the four more (POS_C 0.9213; 0.9188 since i24-chain, which drops a route of the 12 that
    breaks the fill's clearance and fills it again: the test below). Exact but for float
    rounding where the floor keeps that clearance (the credit's sums run in another UAV
    order); measured, not by construction, where it does not, as here."""
    sc, prior = mini(250, 6.25, 1)
    plans = plan_fleets(sc, [16, 12], prior=prior)
    assert [len(p["uavs"]) for p in plans] == [12, 16]
    assert plans[1]["posc"] >= plans[0]["posc"] - 1e-12
    assert plans[1]["optimizer"]["settings"]["fleet"]["floor_uavs"] == 12
    # without fill_apart (on by default: filled routes in eq. 21 conflict are dropped) the
    # four more UAVs are all filled (and with the floor per flight hour off: it sends home
    # filled UAVs that add too little for their hours, tests/planning/test_sent_home.py)
    free = plan_fleets(
        sc, [16, 12], prior=prior, options=PlanOptions(fill_apart=False, gain_per_hour=0)
    )
    assert free[1]["posc"] >= free[0]["posc"] - 1e-12
    assert all(u["waypoints_m"] for u in free[1]["uavs"])


def _idle_plan(sc, fields):
    """A schema-2 plan of one UAV without a route per take-off field in ``fields``."""
    uavs = [{"id": k + 1, "rectangle": None, "spacing_m": 0.0, "takeoff_m": list(t),
             "landing_m": list(t), "waypoints_m": [], "track_length_m": 0.0,
             "flight_time_s": 0.0, "pod": 0.0, "poc": 0.0, "pos": 0.0, "feasible": True}
            for k, t in enumerate(fields)]  # fmt: skip
    return {"schema": 2, "scenario": sc.name, "seed": 0, "map_source": "builtin",
            "optimizer": {"name": "allocation", "settings": {}}, "runtime_s": 0.0,
            "posc": 0.5, "upper_bound": 1.0, "uavs": uavs}  # fmt: skip


def test_a_floor_of_another_fleet_is_refused_before_planning():
    sc, prior = mini(200, 5, 2)
    big = _idle_plan(sc, sc.with_uavs(8).takeoff_m)
    with pytest.raises(ConfigError, match=r"floor\.uavs\[\d\]"):
        make_allocation_plan(sc, prior=prior, floor=big)
    small = {"posc": 0.0, "uavs": []}
    with pytest.raises(ConfigError, match="also_default"):
        make_allocation_plan(sc, prior=prior, floor=small, options=PlanOptions(also_default=True))


@pytest.mark.parametrize(
    ("floor", "field"),
    [("x", "floor"), ({}, "floor.schema"), ({"posc": 2.0}, "floor.posc"),
     ({"uavs": [{"id": 1}]}, "floor.uavs[0].feasible")],
)  # fmt: skip
def test_a_floor_that_is_not_a_plan_is_refused_naming_the_field(floor, field):
    """i24-dayaudit: ``floor="x"`` raised AttributeError, ``{}`` KeyError."""
    sc, prior = mini(200, 5, 2)
    if isinstance(floor, dict) and floor:  # a plan with that field wrong
        floor = {**_idle_plan(sc, sc.takeoff_m[:1]), **floor}
    with pytest.raises(ConfigError, match=rf"^{re.escape(field)}: got "):
        make_allocation_plan(sc, prior=prior, floor=floor)


@pytest.mark.parametrize(
    ("sizes", "message"),
    [(0, "sizes: got 0"), (65, "sizes: got 65"), ([], "sizes: got []"), ("x", "sizes: got 'x'"),
     ([4, 0], "sizes[1]: got 0"), ([4, "x"], "sizes[1]: got 'x'"), ([4.5], "sizes[0]: got 4.5")],
)  # fmt: skip
def test_plan_fleets_names_a_bad_size(sizes, message):
    """Every fleet size in [1, 64], a list's bad entry named by its index (i24-dayaudit: ``[4,
    0]`` was refused as ``sizes: got 0``), before any planning."""
    sc, prior = mini(200, 5, 2)
    with pytest.raises(ConfigError, match="^" + re.escape(message) + "; allowed: "):
        plan_fleets(sc, sizes, prior=prior)


#: i24-deconflict's two cases on ``large_400`` at 10 km cells (results/plan_scale/
#: i24-deconflict/repro.py): the zone, the sightings (x km, y km, weight) and the UAVs
LANES = ([[40, 20], [120, 20], [120, 60], [40, 60]], [(80, 110, 0.5), (80, 200, 0.5)], 6)
MONO2 = (
    [[100, 150], [175, 150], [175, 225], [100, 225]],
    [(160.9, 151.6, 0.1), (139.1, 226.6, 0.1), (301.6, 45.3, 0.06), (123.4, 98.4, 0.12),
     (373.4, 126.6, 0.1), (251.6, 273.4, 0.06), (26.6, 380, 0.15), (160.9, 380, 0.09),
     (307.8, 380, 0.04)],
    12,
)  # fmt: skip


@pytest.mark.parametrize("case", [LANES, MONO2], ids=["lanes", "mono2"])
def test_greedy_rectangles_gives_distinct_routes_where_distinct_rectangles_exist(case):
    """``lanes``: a zone between airfield A and two sightings; the first UAV's route was cut
    by eq. 18 to the way round the zone and home (the check that it kept half its lines
    counted the waypoints round the zone), it swept no rectangle cell, so the cells were not
    taken and UAVs 1 and 2 flew one identical route. ``mono2``: sightings inside a zone's edge;
    the lines clipped to searchable airspace did not cover the cells as flown, and UAVs 3-4
    and 11-12 flew identical routes. Now each UAV takes the best remaining rectangle, or
    none."""
    zone, pts, n = case
    sc = load_scenario("large_400", {"map.cell_km": 10, "map.no_fly_zones_km": [zone]})
    sc = sc.with_uavs(n)
    prior = np.zeros(Grid.from_config(sc.map).shape)
    for x, y, m in pts:
        prior[int(y // 10), int(x // 10)] += m
    plan = make_greedy_rectangles_plan(sc, prior=prior / prior.sum())
    routes = [tuple(map(tuple, np.round(u["waypoints_m"]))) for u in plan["uavs"]]
    flown = [r for r in routes if r]
    assert len(flown) >= 2
    assert len(set(flown)) == len(flown)


def _conflict_steps(sc, plan) -> int:
    """Planned conflict pair-steps of ``plan`` at the fill's clearance (``FILL_WITHIN`` x d_s,
    :func:`~poc_env.agents.planning.deconflict.conflicts`)."""
    sc = sc.with_uavs(len(plan["uavs"]))
    routes = [u["waypoints_m"] for u in plan["uavs"]]
    _, pos, act = planned_positions(sc, routes, plan_speeds(sc, SPEED))
    return int(conflicts(sc, pos, act, within=FILL_WITHIN).sum()) // 2


def test_a_chained_plan_keeps_the_fills_clearance():
    """i24-chain: the 12-UAV plan alone (``half_fleet`` and ``own_apart`` off: as the default
    planned it before)
    has two UAVs within ``FILL_WITHIN`` x d_s at planned times (13 pair-steps: the starts' own
    routes are not parted). The 16-UAV plan with it as its floor keeps its routes, but only
    those that keep the fill's clearance (``deconflict.apart``, the fill's own check): the
    later UAV of the pair is given a new route with the four added UAVs, and the plan has no
    conflict at that clearance (before i24-chain the floor's routes were kept as they were,
    the pair's steps with them). It still plans more than the 12 here, not by construction
    once a route is dropped."""
    sc, prior = mini(250, 6.25, 1)
    before = PlanOptions(half_fleet=False, own_apart=False)
    small = make_allocation_plan(sc.with_uavs(12), prior=prior, options=before)
    big = make_allocation_plan(sc.with_uavs(16), prior=prior, floor=small)
    assert _conflict_steps(sc, small) > 0  # the premise: the floor's own routes conflict
    assert big["optimizer"]["settings"]["fleet"]["kept"] == "floor"
    assert _conflict_steps(sc, big) == 0
    assert big["posc"] >= small["posc"]
    # the floor's routes that keep the clearance are kept as they were, the others not
    kept = {tuple(map(tuple, u["waypoints_m"])) for u in small["uavs"] if u["waypoints_m"]}
    now = {tuple(map(tuple, u["waypoints_m"])) for u in big["uavs"] if u["waypoints_m"]}
    assert 0 < len(kept - now) < len(kept)


def test_a_fleet_larger_than_its_plan_uses_plans_no_less_than_half_of_it():
    """i24-chain, ``PlanOptions.half_fleet`` (on): 32 UAVs alone plan 0.9156 with 20 UAVs
    without a route, below the 0.9166 of 16 UAVs (measured with ``half_fleet=False``). A plan
    that leaves a UAV without a route is compared with the default plan of half the fleet,
    its routes kept and the other UAVs filled (``plan_fleets``' floor): here that is kept
    (0.9193), so 32 UAVs plan no less than 16. (With i24-monotone's
    ``three_quarter_from=32`` 32 UAVs are compared with three quarters of the fleet, 24, too:
    the slow test below.) By
    construction where the half fleet's plan keeps the fill's clearance, as here (then no
    route of it is dropped and the fill only adds)."""
    sc, prior = mini(250, 6.25, 1)
    half = make_allocation_plan(sc.with_uavs(16), prior=prior)
    plan = make_allocation_plan(sc.with_uavs(32), prior=prior)
    fleet = plan["optimizer"]["settings"]["fleet"]
    assert fleet["floor"] == "half_fleet" and fleet["floor_uavs"] == 16
    assert fleet["floor_posc"] == half["posc"]  # the half fleet's own default plan
    assert _conflict_steps(sc, half) == 0  # the claim's condition
    assert plan["posc"] >= half["posc"] - 1e-12


def test_a_kept_half_fleet_floor_flies_no_uav_below_its_floor_per_hour():
    """i24-chain x i24-gainhour: where the half fleet's plan is kept (here 24 UAVs on a 300 km
    square of 7.5 km cells), the UAVs the fill adds to it go through the floor per flight hour
    too: without that, 13 of its 21 flying UAVs added less than 1e-4 of the mass per hour (on
    the 500 km audit scenario 12 of 20, one flying 0.10 h for nothing)."""
    sc, prior = mini(300, 7.5, 24)
    plan = make_allocation_plan(sc, prior=prior)
    assert plan["optimizer"]["settings"]["fleet"]["kept"] == "floor"
    grid = Grid.from_config(sc.map)
    paths = [[u["takeoff_m"], *u["waypoints_m"], u["landing_m"]] if u["waypoints_m"] else []
             for u in plan["uavs"]]  # fmt: skip
    total = sum(sampled_sweep(sc, grid, prior, paths)[0])
    floor = PlanOptions().gain_per_hour * float(prior.sum())
    flying = [k for k, p in enumerate(paths) if p]
    assert len(flying) > 1
    for k in flying:
        rest = [[] if j == k else q for j, q in enumerate(paths)]
        added = total - sum(sampled_sweep(sc, grid, prior, rest)[0])
        assert added >= floor * plan["uavs"][k]["flight_time_s"] / 3600, k


def _reward_value(sc, plan) -> float:
    """Planned POS less the environment's violation penalty at the planned positions."""
    return plan["posc"] - violation_penalty(sc, [u["waypoints_m"] for u in plan["uavs"]])


def test_own_routes_in_conflict_are_cleared_where_it_pays():
    """12 UAVs on ``mini`` (``half_fleet`` off): the plan's own routes have 13 pair-steps
    within ``FILL_WITHIN`` x d_s at planned times; with ``own_apart`` the later UAVs of the
    conflicts are dropped and filled anew (the fill's rule, which may leave a UAV idle), no
    conflict is left, and the plan finds no less POS less the violation penalty than the own
    plan (0.0039 less POS, 0.0042 less penalty)."""
    sc, prior = mini(250, 6.25, 12)
    base = {"half_fleet": False}
    own = make_allocation_plan(sc, prior=prior, options=PlanOptions(own_apart=False, **base))
    plan = make_allocation_plan(sc, prior=prior, options=PlanOptions(**base))
    assert _conflict_steps(sc, own) > 0  # the premise: the own routes conflict
    assert plan["optimizer"]["settings"]["own_apart"]["kept"] == "cleared"
    assert _conflict_steps(sc, plan) == 0
    assert _reward_value(sc, plan) >= _reward_value(sc, own)


def test_own_routes_are_kept_where_clearing_would_gut_the_plan():
    """``small`` (8 UAVs on 40 x 40 cells): clearing drops 6 of the 8 routes and the fill
    finds 0.50 where the plan finds 0.89 (i24-chain measured 0.6182 through the half fleet);
    the rule keeps the own plan, waypoint for waypoint, and records why."""
    sc = load_scenario("small")
    own = make_allocation_plan(sc, options=PlanOptions(own_apart=False))
    plan = make_allocation_plan(sc)
    rec = plan["optimizer"]["settings"]["own_apart"]
    assert rec["kept"] == "own" and rec["dropped"] > 0
    assert rec["pos"][1] - rec["penalty"][1] < rec["pos"][0] - rec["penalty"][0]
    assert [u["waypoints_m"] for u in plan["uavs"]] == [u["waypoints_m"] for u in own["uavs"]]
    assert plan["posc"] == own["posc"]


def _criterion(plan, prior) -> float:
    """The pick's criterion (``_pick``, i24-gainhour): planned POS less ``gain_per_hour`` of
    the prior's mass per eq. 17 flight hour times the plan's flight hours (the default has no
    violation penalty in the pick)."""
    hours = sum(u["flight_time_s"] for u in plan["uavs"]) / 3600
    return plan["posc"] - PlanOptions().gain_per_hour * float(prior.sum()) * hours


def test_three_quarters_of_the_fleet_lift_twelve_uavs_above_eight():
    """i24-monotone's rule where it is cheap (40 x 40 cells, 4 s of CPU): on this 200 km case
    12 UAVs planned less than 8 in the pick's own criterion (0.910129 against 0.913653): the
    12-UAV plan is compared with its half fleet (6) only. With ``three_quarter_from=12`` it is
    compared with three quarters of it (9) too, lifted, and plans no less than 8 (0.919508; up
    to ``nothing``, the pick's tie). Off by default (the flown clearance at 32 UAVs,
    docs/PLANNER.md): the default plan is the one that fell."""
    sc, prior = mini(200, 5, 1)
    fewer = make_allocation_plan(sc.with_uavs(8), prior=prior)
    more = make_allocation_plan(
        sc.with_uavs(12), prior=prior, options=PlanOptions(three_quarter_from=12)
    )
    tie = PlanOptions().nothing * float(prior.sum())
    assert _criterion(more, prior) >= _criterion(fewer, prior) - tie
    fleet = more["optimizer"]["settings"]["fleet"]
    assert [f["uavs"] for f in fleet["floors"]] == [6, 9]


@pytest.mark.slow
def test_more_uavs_never_plan_less_than_three_quarters_of_them():
    """i24-monotone: on this case 32 UAVs planned less than 24 in the pick's own criterion
    (0.914887 against 0.915944; planned POS_C 0.9166 against 0.9180): the 32-UAV plan was
    compared with its half fleet (16) only, 24's plan with 12, and 12's routes leave the fill
    more to fly than 16's. From ``three_quarter_from`` (32) UAVs a plan that leaves a UAV
    without a route is also compared with three quarters of its fleet (24) lifted, so 32 UAVs
    plan no less than 24 (up to ``nothing``, the pick's tie, in which it flies fewer hours).
    Slow (a second 32-UAV plan, 25-50 s); the test above checks the rule in seconds."""
    sc, prior = mini(250, 6.25, 1)
    fewer = make_allocation_plan(sc.with_uavs(24), prior=prior)
    opt = PlanOptions(three_quarter_from=32)
    more = make_allocation_plan(sc.with_uavs(32), prior=prior, options=opt)
    tie = PlanOptions().nothing * float(prior.sum())
    assert _criterion(more, prior) >= _criterion(fewer, prior) - tie
    fleet = more["optimizer"]["settings"]["fleet"]
    assert [f["uavs"] for f in fleet["floors"]] == [16, 24]
