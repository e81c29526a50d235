"""The regrade (i24-regrade): runs of lawnmower lines re-spaced jointly in the environment's
sensor model."""

import numpy as np
import pytest

from poc_env.agents.planning.allocation import make_allocation_plan, sampled_sweep
from poc_env.agents.planning.flight_rules import plan_speeds, reserve_s
from poc_env.agents.planning.options import PlanOptions
from poc_env.agents.planning.polish import polish_for
from poc_env.agents.planning.refine import Airspace, route_fits, track
from poc_env.agents.planning.regrade import find_runs, regrade_routes
from poc_env.agents.testing.routes import assert_flyable_inside
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.sim.core import takeoff_heading
from poc_env.theory.probability_map import Grid, build_prior

W = 5000.0


def _lawnmower(ys, x0=15000.0, x1=25000.0):
    """Lines along x at the heights ``ys``, turning at alternate ends."""
    pts = []
    for j, y in enumerate(ys):
        a, b = (x0, x1) if j % 2 == 0 else (x1, x0)
        pts += [[a, float(y)], [b, float(y)]]
    return pts


def _setup(sc):
    grid = Grid.from_config(sc.map)
    takeoff = np.asarray(sc.takeoff_m, dtype=float).reshape(-1, 2)
    landing = np.asarray(sc.landing_m, dtype=float).reshape(-1, 2)
    return grid, takeoff, landing


def _sampled(sc, routes, prior) -> float:
    grid, takeoff, landing = _setup(sc)
    paths = [[takeoff[k], *r, landing[k]] if r else [] for k, r in enumerate(routes)]
    return float(sum(sampled_sweep(sc, grid, prior, paths)[0]))


def test_runs_of_a_hand_made_lawnmower():
    """Take-off, a transit waypoint, five lines of a lawnmower, a transit waypoint, landing:
    one run of five lines starting at the first line's first waypoint; a line turned by 45
    degrees ends the run there; a line half as long again as its neighbour still belongs, a
    line a quarter as long does not; too few lines are no run; the connectors are no run."""
    mower = _lawnmower([10000.0, 18000.0, 26000.0, 34000.0, 42000.0], x0=10000.0, x1=60000.0)
    path = [[0.0, -50000.0], [5000.0, 0.0], *mower, [70000.0, 60000.0], [90000.0, -50000.0]]
    assert find_runs(path, W) == [(2, 5)]
    assert find_runs(path, W, min_lines=6) == []
    turned = [list(p) for p in path]
    turned[9] = [turned[8][0] + 30000.0, turned[8][1] + 30000.0]  # the fourth line turned
    assert find_runs(turned, W) == [(2, 3)]
    short = [list(p) for p in path]
    short[7][0] = 20000.0  # the third line (10 -> 60 km along x) a fifth as long
    assert find_runs(short, W) == []  # 2 lines, then 2: no run of 3
    longer = [list(p) for p in path]
    longer[6][0] = -10000.0  # the third line 1.4 times as long
    assert find_runs(longer, W) == [(2, 5)]
    # the connectors alone (legs along y, all the same way) are no run
    conn = [[0.0, -1000.0], *[[0.0, float(y)] for y in range(0, 50000, 8000)], [0.0, 60000.0]]
    assert find_runs(conn, W, min_lines=2) == []


def test_lines_get_denser_where_the_mass_is():
    """One UAV sweeps five lines 4 km apart over a box whose mass lies in its lowest row of
    cells (y 10-15 km) with a little above: the regrade lays more of the lines over the mass,
    closer together than before, gains planned POS and keeps the route flyable."""
    sc = load_scenario("small").with_uavs(1)
    grid, takeoff, landing = _setup(sc)
    prior = np.full(grid.shape, 0.002)
    prior[2, 3:5] = 0.2  # small: 8 x 8 cells of 5 km; row 2 is y 10-15 km
    prior /= prior.sum()
    ys = [11000.0, 15000.0, 19000.0, 23000.0, 27000.0]
    routes = [_lawnmower(ys)]
    v = plan_speeds(sc)
    heading = takeoff_heading(grid.bounds, takeoff)
    fits = (v, sc.uav.max_turn_rate_rad_s, sc.uav.usable_endurance_s, reserve_s(sc))
    assert route_fits(np.vstack([takeoff[0], routes[0], landing[0]]), *fits, heading[0])
    out, value, stats = polish_for(sc, routes, prior, 1, airspace=False, routine=regrade_routes,
                                   counts=(0,))  # fmt: skip
    assert stats["moves"] == 1 and stats["runs"] == 1
    assert value > _sampled(sc, routes, prior) + 1e-3
    assert value == pytest.approx(_sampled(sc, out, prior), rel=1e-9)
    r = np.asarray(out[0])
    assert r.shape == (10, 2)
    assert np.allclose(r[0::2, 1], r[1::2, 1])  # lines along x still
    y = np.sort(r[0::2, 1])
    in_mass = y[(y >= 10000.0) & (y <= 15000.0)]
    assert len(in_mass) > 2  # 2 of the 5 lines before (11 and 15 km)
    assert np.diff(in_mass).max() < 4000.0 - 1e-6  # denser there than the 4 km before
    assert route_fits(np.vstack([takeoff[0], r, landing[0]]), *fits, heading[0])


def test_regrade_never_lowers_planned_pos_and_keeps_routes_flyable():
    """On a random prior of paper_6_2's, the default plan regraded (airspace check on): the
    planned POS rises and is the environment's sweep of the routes, every route fits eq. 17-18,
    every waypoint lies inside the map and the eq. 21 / 24 violations at the planned positions
    do not rise."""
    from poc_env.agents.experiments.evaluate import episode_prior

    sc = load_scenario("paper_6_2")
    prior = episode_prior(sc, 7)
    grid, takeoff, landing = _setup(sc)
    routes = [u["waypoints_m"] for u in make_allocation_plan(sc, prior=prior)["uavs"]]
    before = _sampled(sc, routes, prior)
    out, value, stats = polish_for(sc, routes, prior, 1, routine=regrade_routes)
    assert stats["moves"] > 0
    assert value > before + 1e-4
    assert value == pytest.approx(_sampled(sc, out, prior), rel=1e-9)
    v = plan_speeds(sc)
    heading = takeoff_heading(grid.bounds, takeoff)
    air = Airspace(sc.episode.dt_s, 2.0 * sc.constraints.safety_distance_m,
                   0.9 * sc.comms.range_m, sc.comms.min_neighbours)  # fmt: skip
    times = np.arange(int(np.ceil(sc.uav.usable_endurance_s / air.dt_s)) + 1) * air.dt_s

    def count(rs):
        pos = np.zeros((len(times), len(rs), 2))
        act = np.zeros((len(times), len(rs)), dtype=bool)
        for k, r in enumerate(rs):
            if r:
                path = np.vstack([takeoff[k], np.asarray(r), landing[k]])
                pos[:, k], act[:, k] = track(path, v, sc.uav.max_turn_rate_rad_s, times,
                                             heading[k])  # fmt: skip
        return air.violations(pos, act)

    assert_flyable_inside(sc, grid, takeoff, landing, out, routes)
    assert count(out) <= count(routes)


def test_regrade_arguments_and_options_are_checked():
    sc = load_scenario("small")
    for kw, field in (({"counts": (0, 4)}, "counts"), ({"min_lines": 1}, "min_lines"),
                      ({"radii": (0.0,)}, "radii"), ({"passes": -1}, "passes")):  # fmt: skip
        with pytest.raises(ConfigError, match=field):
            polish_for(sc, [[]] * sc.n_uavs, np.ones((8, 8)), kw.pop("passes", 1),
                       routine=regrade_routes, **kw)  # fmt: skip
    with pytest.raises(ConfigError, match=r"options\.regrade"):
        PlanOptions(regrade=-1)
    with pytest.raises(ConfigError, match=r"options\.regrade_at"):
        PlanOptions(regrade_at="last")


@pytest.mark.parametrize("where", ["first", "between", "end"])
def test_regrade_option_reaches_the_plan(where):
    """``regrade`` > 0 runs the stage where ``regrade_at`` says (its kept moves recorded as
    ``regrade_moves``) and the plan is the environment's sweep of its routes; 0 (the default)
    runs none."""
    sc = load_scenario("small")
    base = PlanOptions(polish=1, polish_lines=1, polish_grade=True)
    a = make_allocation_plan(sc, options=base)
    b = make_allocation_plan(
        sc,
        options=PlanOptions(
            polish=1, polish_lines=1, polish_grade=True, regrade=1, regrade_at=where
        ),
    )
    assert "regrade_moves" not in a["optimizer"]["settings"]["polish"]
    st = b["optimizer"]["settings"]["polish"]
    assert st["regrade_moves"] >= 0 and st["runs"] > 0
    paths = [[u["takeoff_m"], *u["waypoints_m"], u["landing_m"]] if u["waypoints_m"] else []
             for u in b["uavs"]]  # fmt: skip
    grid = Grid.from_config(sc.map)
    prior = build_prior(sc.map)
    assert b["posc"] == pytest.approx(float(sum(sampled_sweep(sc, grid, prior, paths)[0])))
