"""The polish's box moves (i24-boxes): a route's box, or an airfield's group of search parts,
translated, stretched or turned as one (agents/planning/polish.py, ``PlanOptions.polish_boxes``)."""

import numpy as np
import pytest

from poc_env.agents.planning.allocation import make_allocation_plan, sampled_sweep
from poc_env.agents.planning.flight_rules import plan_speeds, reserve_s
from poc_env.agents.planning.options import THOROUGH, PlanOptions
from poc_env.agents.planning.polish import (
    ALL_KINDS,
    BOX_KINDS,
    KINDS,
    MOVES,
    polish_for,
)
from poc_env.agents.planning.refine import Airspace, route_fits
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.sim.core import takeoff_heading
from poc_env.theory.probability_map import Grid


def _setup(sc):
    grid = Grid.from_config(sc.map)
    takeoff = np.asarray(sc.takeoff_m, dtype=float).reshape(-1, 2)
    landing = np.asarray(sc.landing_m, dtype=float).reshape(-1, 2)
    return grid, takeoff, landing


def _polish(sc, routes, prior, passes=2, airspace=True, **kw):
    """polish_routes as the planner calls it (:func:`polish_for`), 2 passes."""
    return polish_for(sc, routes, prior, passes, airspace=airspace, **kw)


def _sampled(sc, routes, prior) -> float:
    grid, takeoff, landing = _setup(sc)
    paths = [[takeoff[k], *r, landing[k]] if r else [] for k, r in enumerate(routes)]
    return float(sum(sampled_sweep(sc, grid, prior, paths)[0]))


def _lawnmower(ys, x0, x1):
    """Lines along x at the heights ``ys``, turning at alternate ends."""
    pts = []
    for j, y in enumerate(ys):
        a, b = (x0, x1) if j % 2 == 0 else (x1, x0)
        pts += [[a, float(y)], [b, float(y)]]
    return pts


def _similarity_residual(old: np.ndarray, new: np.ndarray) -> float:
    """The largest distance (m) between ``new`` and the best similarity transform (turn,
    uniform scale, translation) of ``old``: 0 when the points moved as one rigid, scaled
    figure."""
    z0 = old[:, 0] + 1j * old[:, 1]
    z1 = new[:, 0] + 1j * new[:, 1]
    a_mat = np.stack([z0, np.ones_like(z0)], axis=1)
    coef, *_ = np.linalg.lstsq(a_mat, z1, rcond=None)
    return float(np.max(np.abs(a_mat @ coef - z1)))


def _flyable_inside(sc, out):
    """Every route fits eq. 17-18 (route_fits) and every waypoint lies inside the map."""
    grid, takeoff, landing = _setup(sc)
    v = plan_speeds(sc)
    heading = takeoff_heading(grid.bounds, takeoff)
    fits = (v, sc.uav.max_turn_rate_rad_s, sc.uav.usable_endurance_s, reserve_s(sc))
    x0, y0, x1, y1 = grid.bounds
    for k, r in enumerate(out):
        r = np.asarray(r).reshape(-1, 2)
        if len(r):
            assert route_fits(np.vstack([takeoff[k], r, landing[k]]), *fits, heading[k])
            assert np.all((r >= [x0, y0]) & (r <= [x1, y1]))


def test_box_kinds_are_named_explicitly_and_off_by_default():
    """The box moves are tried only where named: not in the polish's default moves nor in
    the kinds the polish and the second polish use, the option is off by default and
    ``thorough`` does not set it (so its plans are unchanged)."""
    assert set(BOX_KINDS) <= set(ALL_KINDS)
    assert not set(BOX_KINDS) & set(KINDS) and not set(BOX_KINDS) & set(MOVES)
    assert PlanOptions().polish_boxes == 0 and "polish_boxes" not in THOROUGH
    assert PlanOptions.preset("thorough").polish_boxes == 0


def test_a_box_move_carries_a_box_far_onto_the_mass():
    """One UAV sweeps three lines 2.5 km apart (W) at x 5-12.5 km, y 5-10 km; the mass lies
    in the cells x 25-35 km, y 25-35 km, more than 2 W (the waypoint moves' radii) from every
    line: with only box moves the polish carries the whole box towards the mass (its shape
    kept: every waypoint moved by the same vector), gains planned POS, and keeps the route
    flyable and inside the map."""
    sc = load_scenario("small").with_uavs(1)
    grid, _, _ = _setup(sc)
    prior = np.zeros(grid.shape)
    prior[5:7, 5:7] = 0.25  # rows y 25-35, columns x 25-35 (8 x 8 cells of 5 km)
    routes = [_lawnmower([5000.0, 7500.0, 10000.0], x0=5000.0, x1=12500.0)]
    before = _sampled(sc, routes, prior)
    out, value, stats = _polish(sc, routes, prior, passes=4, airspace=False, moves=("box",))
    assert stats["box_moves"] > 0 and value > before + 1e-2
    assert value == pytest.approx(_sampled(sc, out, prior), rel=1e-9)
    r, r0 = np.asarray(out[0]), np.asarray(routes[0])
    assert r.shape == r0.shape
    shift = (r - r0).mean(axis=0)
    assert shift[0] > 5000.0 and shift[1] > 5000.0  # more than 2 W towards the mass
    _flyable_inside(sc, out)


def test_a_trim_move_translates_a_box_and_drops_an_end():
    """The box of the box test with only trim moves (a box translated with one or two end
    waypoints dropped): the polish carries what is left of it towards the mass, gains, and
    the route is shorter by the dropped waypoints, flyable and inside the map."""
    sc = load_scenario("small").with_uavs(1)
    grid, _, _ = _setup(sc)
    prior = np.zeros(grid.shape)
    prior[5:7, 5:7] = 0.25
    routes = [_lawnmower([5000.0, 7500.0, 10000.0], x0=5000.0, x1=12500.0)]
    before = _sampled(sc, routes, prior)
    out, value, stats = _polish(sc, routes, prior, passes=2, airspace=False, moves=("trim",))
    assert stats["box_moves"] > 0 and value > before + 1e-2
    assert value == pytest.approx(_sampled(sc, out, prior), rel=1e-9)
    r, r0 = np.asarray(out[0]), np.asarray(routes[0])
    assert len(r) < len(r0)
    assert r[:, 0].mean() > r0[:, 0].mean() + 5000.0 and r[:, 1].mean() > r0[:, 1].mean() + 5000.0
    _flyable_inside(sc, out)


def test_a_stretch_move_squeezes_a_wide_box_onto_rich_mass():
    """One UAV sweeps three lines 7.5 km apart (3 W) over y 5-20 km; the mass lies in one row
    of cells (y 10-15 km) about the middle line: with only stretch moves the box is squeezed
    across its lines (their span smaller, each still along x), gains and stays flyable."""
    sc = load_scenario("small").with_uavs(1)
    grid, _, _ = _setup(sc)
    prior = np.zeros(grid.shape)
    prior[2, 3:5] = 0.5
    routes = [_lawnmower([5000.0, 12500.0, 20000.0], x0=15000.0, x1=25000.0)]
    before = _sampled(sc, routes, prior)
    out, value, stats = _polish(sc, routes, prior, passes=3, airspace=False, moves=("stretch",))
    assert stats["box_moves"] > 0 and value > before + 1e-3
    r = np.asarray(out[0])
    assert r.shape == (6, 2)
    assert np.ptp(r[:, 1]) < 15000.0 - 1000.0  # the lines' span across them squeezed
    _flyable_inside(sc, out)


def test_a_rotate_move_turns_a_search_part_towards_the_mass():
    """One UAV flies out from the airfield (20, -5) km up the map's west side and back; the
    mass lies in the east column of cells: with only rotate moves its route is turned about
    the airfield (the legs from and back to it keep their lengths) towards the mass, and
    gains."""
    sc = load_scenario("small").with_uavs(1)
    grid, _, _ = _setup(sc)
    prior = np.zeros(grid.shape)
    prior[2:6, 6:8] = 1.0 / 8.0  # x 30-40 km, y 10-30 km
    routes = [[[12000.0, 10000.0], [10000.0, 25000.0], [14000.0, 25000.0], [16000.0, 10000.0]]]
    before = _sampled(sc, routes, prior)
    out, value, stats = _polish(sc, routes, prior, passes=4, airspace=False, moves=("rotate",))
    assert stats["box_moves"] > 0 and value > before + 1e-3
    r, r0 = np.asarray(out[0]), np.asarray(routes[0])
    assert r[:, 0].mean() > r0[:, 0].mean() + 2000.0  # turned east, towards the mass
    assert r.shape == r0.shape
    _flyable_inside(sc, out)


def test_a_rotate_move_of_the_whole_search_part_turns_it_about_the_airfield():
    """With one inner waypoint (its box the whole search part, before it and after it the
    airfield) a rotate move turns it about the airfield: it keeps its distance from it, so
    both legs keep their lengths, and it is carried towards the mass."""
    sc = load_scenario("small").with_uavs(1)
    grid, takeoff, _ = _setup(sc)
    prior = np.zeros(grid.shape)
    prior[2:6, 6:8] = 1.0 / 8.0
    routes = [[[12000.0, 20000.0]]]
    out, value, stats = _polish(sc, routes, prior, passes=2, airspace=False, moves=("rotate",))
    r, r0 = np.asarray(out[0]), np.asarray(routes[0])
    assert stats["box_moves"] > 0 and value > _sampled(sc, routes, prior) + 1e-3
    d, d0 = np.hypot(*(r - takeoff[0]).T), np.hypot(*(r0 - takeoff[0]).T)
    assert np.allclose(d, d0, atol=1e-3) and r[:, 0].mean() > r0[:, 0].mean() + 1000.0


def test_a_group_move_carries_an_airfields_group_together():
    """Two UAVs of small's one airfield sweep interleaved lines 2 W apart at x 5-15 km, y 5-12.5
    km; the mass lies at x 20-30 km, y 20-30 km: with only group moves both search parts are
    carried together (one translation, or one turn about the airfield, for both: the
    interleave kept), the pair gains and both routes stay flyable."""
    sc = load_scenario("small").with_uavs(2)
    grid, _, _ = _setup(sc)
    prior = np.zeros(grid.shape)
    prior[4:6, 4:6] = 0.25
    routes = [
        _lawnmower([5000.0, 10000.0], x0=5000.0, x1=15000.0),
        _lawnmower([7500.0, 12500.0], x0=5000.0, x1=15000.0),
    ]
    before = _sampled(sc, routes, prior)
    out, value, stats = _polish(sc, routes, prior, passes=3, airspace=False, moves=("group",))
    assert stats["box_moves"] > 0 and value > before + 1e-3
    assert value == pytest.approx(_sampled(sc, out, prior), rel=1e-9)
    new, old = np.vstack(out), np.vstack(routes)
    assert _similarity_residual(old, new) < 1.0  # both moved by one transform: interleave kept
    assert new[:, 1].mean() > old[:, 1].mean() + 2000.0  # towards the mass
    _flyable_inside(sc, out)


def test_a_group_move_adds_no_airspace_violation():
    """The same pair with the airspace check on: their interleaved lines carried further out
    would fly close together for longer (eq. 21), so the group move keeps only candidates
    after which the swarm's violations at the planned positions do not rise (here none:
    the routes stay as they were)."""
    from poc_env.agents.planning.refine import track

    sc = load_scenario("small").with_uavs(2)
    grid, takeoff, landing = _setup(sc)
    prior = np.zeros(grid.shape)
    prior[4:6, 4:6] = 0.25
    routes = [
        _lawnmower([5000.0, 10000.0], x0=5000.0, x1=15000.0),
        _lawnmower([7500.0, 12500.0], x0=5000.0, x1=15000.0),
    ]
    air = Airspace(sc.episode.dt_s, 2.0 * sc.constraints.safety_distance_m,
                   0.9 * sc.comms.range_m, sc.comms.min_neighbours)  # fmt: skip
    heading = takeoff_heading(grid.bounds, takeoff)
    times = np.arange(int(np.ceil(sc.uav.usable_endurance_s / air.dt_s)) + 1) * air.dt_s

    def count(rs):
        pos = np.zeros((len(times), 2, 2))
        act = np.zeros((len(times), 2), dtype=bool)
        for k, r in enumerate(rs):
            path = np.vstack([takeoff[k], np.asarray(r), landing[k]])
            pos[:, k], act[:, k] = track(path, plan_speeds(sc), sc.uav.max_turn_rate_rad_s,
                                         times, heading[k])  # fmt: skip
        return air.violations(pos, act)

    out, _, _ = _polish(sc, routes, prior, passes=3, moves=("group",))
    free, _, _ = _polish(sc, routes, prior, passes=3, airspace=False, moves=("group",))
    assert count(free) > count(routes)  # what the check turns down
    assert count(out) <= count(routes)


@pytest.mark.parametrize("bad", [-1, 1.5, True, 101])
def test_polish_boxes_option_is_checked(bad):
    with pytest.raises(ConfigError, match=r"options\.polish_boxes"):
        PlanOptions(polish_boxes=bad)


@pytest.mark.parametrize("bad", [(), (2.0, -1.0), (2.0, 65.0), (float("nan"),)])
def test_polish_boxes_radii_option_is_checked(bad):
    with pytest.raises(ConfigError, match=r"options\.polish_boxes_radii"):
        PlanOptions(polish_boxes_radii=bad)


def test_polish_routes_box_radii_are_checked():
    sc = load_scenario("small").with_uavs(1)
    grid, _, _ = _setup(sc)
    prior = np.ones(grid.shape) / 64
    with pytest.raises(ConfigError, match="box_radii"):
        _polish(sc, [[[5000.0, 5000.0]]], prior, moves=("box",), box_radii=(0.0,))


def test_polish_boxes_option_reaches_the_plan_and_never_plans_less():
    """``polish_boxes`` runs a third polish with the box moves after the polishes: on a
    random prior of small's it keeps box moves (recorded in the settings), never plans less
    POS than the polishes alone, and with the option at 0 the plan is the polishes' own."""
    from poc_env.agents.experiments.evaluate import episode_prior

    sc = load_scenario("small")
    prior = episode_prior(sc, 5003)
    base = PlanOptions(polish=2, polish_grade=True, polish_lines=1)
    a = make_allocation_plan(sc, prior=prior, options=base)
    b = make_allocation_plan(
        sc,
        prior=prior,
        options=PlanOptions(polish=2, polish_grade=True, polish_lines=1, polish_boxes=3),
    )
    st = b["optimizer"]["settings"]
    assert st["options"]["polish_boxes"] == 3 and st["polish"]["box_moves"] > 0
    assert "box_moves" not in a["optimizer"]["settings"]["polish"]
    assert b["posc"] > a["posc"] + 1e-6
    assert [u["waypoints_m"] for u in a["uavs"]] != [u["waypoints_m"] for u in b["uavs"]]
    _flyable_inside(sc, [u["waypoints_m"] for u in b["uavs"]])
