"""Route refinement: local search on waypoints under the eq. 17-18 time rules."""

import numpy as np
import pytest

import poc_env
from poc_env.agents.planning.allocation import (
    _path_coverage,
    make_allocation_plan,
    plan_speeds,
    sampled_sweep,
)
from poc_env.agents.planning.refine import (
    Airspace,
    arrival_times,
    leg_samples,
    refine_routes,
    route_fits,
    route_time,
    swarm_violations,
    track,
)
from poc_env.agents.policies.allocation import AllocationPlanPolicy
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.sim.autopilot import must_return
from poc_env.sim.observations import decode_vector
from poc_env.theory.probability_map import Grid, build_prior
from poc_env.theory.search_theory import pod_from_coverage


def _setup(name="small"):
    sc = load_scenario(name)
    grid = Grid.from_config(sc.map)
    takeoff = np.asarray(sc.takeoff_m, dtype=float).reshape(-1, 2)
    landing = np.asarray(sc.landing_m, dtype=float).reshape(-1, 2)
    return sc, grid, build_prior(sc.map), takeoff, landing


def _planned(routes, takeoff, landing, prior, grid, w, law):
    cov = sum(_path_coverage([takeoff[k], *r, landing[k]], grid, w) for k, r in enumerate(routes))
    return float(np.sum(prior * pod_from_coverage(cov, law)))


def test_arrival_times_are_eq_17_with_turns():
    v = type("V", (), {"out": 10.0, "line": 5.0, "home": 20.0})()
    path = [[0, 0], [100, 0], [100, 50], [100, 50], [0, 50]]  # a repeated point adds nothing
    t = arrival_times(path, v, turn_rate=0.1)
    turn = 0.5 * (np.pi / 2) / 0.1  # TURN_SHARE of a quarter turn at the maximum rate
    assert t[1] == pytest.approx(10.0)
    assert t[2] == pytest.approx(10.0 + turn + 10.0)
    assert t[3] == pytest.approx(t[2])
    assert t[4] == pytest.approx(t[2] + turn + 5.0)
    assert route_time(path, v, 0.1) == pytest.approx(t[-1])


def test_route_fits_applies_eq_18_at_every_waypoint():
    """A route that lands in time but is far from home with little time left is not flown
    whole (the return rule turns the UAV home first), so it does not fit."""
    v = type("V", (), {"out": 10.0, "line": 10.0, "home": 10.0})()
    out_and_back = [[0, 0], [1000, 0], [0, 0]]  # 200 s, never further than 100 s from home
    assert route_fits(out_and_back, v, 1.0, budget=200.0 + 2 * np.pi * 0.5, reserve=0.0)
    assert not route_fits(out_and_back, v, 1.0, budget=150.0, reserve=0.0)  # lands late
    # lands at t = 200 + turns, but at the far point (t = 100) home is 100 s away: with a
    # reserve of 60 s the return rule is due there
    assert not route_fits(out_and_back, v, 1.0, budget=220.0, reserve=60.0)
    assert route_fits(out_and_back, v, 1.0, budget=300.0, reserve=60.0)


def test_refinement_never_lowers_the_planned_pos_and_reports_it():
    sc, grid, prior, takeoff, landing = _setup()
    v = plan_speeds(sc, "max")
    u = sc.uav
    base = make_allocation_plan(sc, refine=0)
    routes = [x["waypoints_m"] for x in base["uavs"]]
    w, law = sc.sensor.sweep_width_m, sc.sensor.law
    before = _planned(routes, takeoff, landing, prior, grid, w, law)
    # the plan reports the environment's model over the whole paths (sampled_sweep); the
    # refinement scores W x length per cell (_planned)
    paths = [[takeoff[k], *r, landing[k]] if r else [] for k, r in enumerate(routes)]
    assert sum(sampled_sweep(sc, grid, prior, paths)[0]) == pytest.approx(base["posc"], abs=1e-12)
    args = (takeoff, landing, prior, grid, w, law, v, u.usable_endurance_s)
    refined, value = refine_routes(routes, *args, u.max_turn_rate_rad_s, 120.0, sweeps=2)
    assert value == pytest.approx(_planned(refined, takeoff, landing, prior, grid, w, law))
    assert value > before  # the small map's lines leave room to improve
    for k, r in enumerate(refined):
        path = np.vstack([takeoff[k], np.asarray(r).reshape(-1, 2), landing[k]])
        assert route_fits(path, v, u.max_turn_rate_rad_s, u.usable_endurance_s, 120.0)
        assert np.all(np.asarray(r)[1:] >= grid.bounds[:2]) and np.all(
            np.asarray(r)[1:] <= grid.bounds[2:]
        )  # moved and inserted waypoints stay in the map (the first may be a dog-leg)
    again, value2 = refine_routes(routes, *args, u.max_turn_rate_rad_s, 120.0, sweeps=2)
    assert again == refined and value2 == value  # deterministic


def test_refined_plan_is_flown_whole_before_the_return_rule():
    """Every UAV of the (refined) plan reaches its last waypoint before eq. 18 turns it home,
    which is what route_fits promises; a plan ignoring the rule is cut short (checked when this
    test was written by dropping the waypoint condition of route_fits)."""
    env = poc_env.parallel_env("small")
    obs, _ = env.reset(seed=3)
    pol = AllocationPlanPolicy()
    pol.reset(env, 3)
    cut = set()
    while env.agents:
        for k, agent in enumerate(env.possible_agents):
            if agent in obs and pol.follower.index[k] < len(pol.follower.waypoints[k]):
                q = decode_vector(env.params, pol.follower._vector(obs[agent]))
                if must_return(env.params, q, k):
                    cut.add(k)
        obs, *_ = env.step(pol.predict(obs)[0])
    assert not cut
    assert env.sim_state.landed[0].all()


def test_speed_rule_is_checked_and_recorded():
    plan = make_allocation_plan("small", speed="paper", refine=0)
    sc = load_scenario("small")
    assert plan["speeds_mps"] == {
        "out": sc.uav.cruise_speed_mps,
        "line": sc.uav.search_speed_mps,
        "home": sc.uav.cruise_speed_mps,
    }
    assert make_allocation_plan("small", refine=0)["speeds_mps"]["line"] == sc.uav.max_speed_mps
    with pytest.raises(ConfigError, match="speed"):
        make_allocation_plan("small", speed="fast")
    with pytest.raises(ConfigError, match="refine"):
        make_allocation_plan("small", refine=-1)


def test_track_is_where_the_timing_puts_the_uav():
    v = type("V", (), {"out": 10.0, "line": 10.0, "home": 10.0})()
    path = [[0, 0], [100, 0], [100, 100]]
    t = arrival_times(path, v, turn_rate=1.0)  # a quarter turn costs 0.5 * pi/2 s at (100, 0)
    times = np.array([0.0, 5.0, t[1], t[1] + 0.5, t[2] - 5.0, t[2] + 1.0])
    pos, act = track(path, v, 1.0, times)
    assert np.allclose(pos[:4], [[0, 0], [50, 0], [100, 0], [100, 0]])  # turning in place
    assert np.allclose(pos[4], [100, 50])
    assert act.tolist() == [True] * 5 + [False]  # landed after its last point


def test_swarm_violations_count_the_environments_rules():
    pos = np.array([[[0.0, 0.0], [500.0, 0.0], [5000.0, 0.0]]])  # one time, three UAVs
    act = np.ones((1, 3), dtype=bool)
    # UAVs 0 and 1 are within 1 km; everybody is in range of two others
    assert swarm_violations(pos, act, 1000.0, 10_000.0, 2) == 2
    # a 4 km range leaves UAV 2 alone and UAVs 0, 1 with one neighbour each
    assert swarm_violations(pos, act, 1000.0, 4000.0, 2) == 2 + 3
    act[0, 1] = False  # landed UAVs neither violate nor count as neighbours
    assert swarm_violations(pos, act, 1000.0, 10_000.0, 2) == 0


def test_refinement_adds_no_planned_airspace_violation():
    sc, grid, prior, takeoff, landing = _setup()
    v = plan_speeds(sc, "max")
    u = sc.uav
    routes = [x["waypoints_m"] for x in make_allocation_plan(sc, refine=0)["uavs"]]
    space = Airspace(
        sc.episode.dt_s, 2 * sc.constraints.safety_distance_m, 0.9 * sc.comms.range_m, 2
    )
    times = np.arange(int(np.ceil(u.usable_endurance_s / space.dt_s)) + 1) * space.dt_s

    def planned_violations(rs):
        flights = [
            track(
                np.vstack([takeoff[k], np.reshape(r, (-1, 2)), landing[k]]),
                v,
                u.max_turn_rate_rad_s,
                times,
            )
            for k, r in enumerate(rs)
        ]
        pos = np.stack([f[0] for f in flights], axis=1)
        act = np.stack([f[1] for f in flights], axis=1)
        return space.violations(pos, act)

    args = (takeoff, landing, prior, grid, sc.sensor.sweep_width_m, sc.sensor.law, v)
    free, _ = refine_routes(
        routes, *args, u.usable_endurance_s, u.max_turn_rate_rad_s, 90.0, sweeps=2
    )
    kept, _ = refine_routes(
        routes, *args, u.usable_endurance_s, u.max_turn_rate_rad_s, 90.0, sweeps=2, airspace=space
    )
    trimmed, _ = refine_routes(
        routes, *args, u.usable_endurance_s, u.max_turn_rate_rad_s, 90.0, sweeps=0
    )
    assert planned_violations(kept) <= planned_violations(trimmed)
    assert planned_violations(free) > planned_violations(kept)  # the check is what holds it


def test_move_gains_equal_full_scoring_on_random_moves():
    """The refinement scores a waypoint's candidate moves on the cells they touch only
    (``move_gains``); the coverage there must be the full grid's ``total - old legs + new
    legs`` bit for bit and the gain the full planned POS's change, on random paths and moves
    (moved, deleted and inserted waypoints, legs leaving the map)."""
    from poc_env.agents.planning.refine import leg_coverage, move_gains

    sc, grid, prior, *_ = _setup("small")
    w, law = sc.sensor.sweep_width_m, sc.sensor.law
    p_flat = prior.ravel() / prior.sum()
    x0, y0, x1, y1 = grid.bounds
    span = np.array([x1 - x0, y1 - y0])
    rng = np.random.default_rng(7)
    for trial in range(40):
        pts = np.array([x0, y0]) - 0.1 * span + rng.random((6, 2)) * 1.2 * span
        others = np.array([x0, y0]) + rng.random((4, 2)) * span
        total = leg_coverage(pts[:-1], pts[1:], grid, w)[0]
        total += leg_coverage(others[:-1], others[1:], grid, w)[0]
        i = int(rng.integers(1, 6))  # i == 5: the last point, only insertions
        old = pts[i - 1 : i + 2]
        starts, ends, rows, kinds = [], [], [], []
        for r in range(int(rng.integers(1, 8))):
            if len(old) > 2 and r % 3 != 2:
                q = old[1] + rng.normal(0, 0.2, 2) * span
                legs = [(old[0], q), (q, old[2])] if r % 3 == 0 else [(old[0], old[2])]
                kinds.append(0)
            else:
                q = 0.5 * (old[0] + old[1]) + rng.normal(0, 0.2, 2) * span
                legs = [(old[0], q), (q, old[1])]
                kinds.append(1)
            for s, e in legs:
                starts.append(s)
                ends.append(e)
                rows.append(r)
        cells, cand, gain = move_gains(total, p_flat, grid, w, law, starts, ends, rows, kinds, old)
        full_new = leg_coverage(starts, ends, grid, w, np.asarray(rows))
        old_a = leg_coverage(old[0], old[1], grid, w)[0]
        old_b = leg_coverage(old[1], old[2], grid, w)[0] if len(old) > 2 else 0.0
        base = np.where(np.asarray(kinds)[:, None] == 0, total - old_a - old_b, total - old_a)
        full = base + full_new
        changed = np.flatnonzero(np.any(full != total[None], axis=0))
        assert np.all(np.isin(changed, cells)), trial
        assert np.array_equal(full[:, cells], cand), trial
        value = p_flat @ pod_from_coverage(total, law)
        np.testing.assert_allclose(value + gain, pod_from_coverage(full, law) @ p_flat, atol=1e-12)


def test_airspace_count_equals_the_full_count_after_moves():
    """The refinement's airspace check counts only the moved UAV's pairs with the others; after
    every move (positions and flying steps changed, UAVs landing early or late) its count must
    equal the full count from scratch, and a move not kept must change nothing."""
    from poc_env.agents.planning.refine import AirspaceCount

    rng = np.random.default_rng(3)
    air = Airspace(60.0, 1500.0, 5000.0, 2)
    pos = rng.normal(0, 3000.0, (50, 7, 2))
    act = rng.random((50, 7)) > 0.2
    count = AirspaceCount(air, pos, act)
    assert count.value == swarm_violations(pos, act, 1500.0, 5000.0, 2)
    for trial, k in enumerate((0, 4, 6, 4, 1, 1)):
        new_pos = rng.normal(0, 3000.0, (50, 2))
        new_act = rng.random(50) > 0.3 * (trial % 3)
        value, state = count.move(k, new_pos, new_act)
        assert count.value == swarm_violations(pos, act, 1500.0, 5000.0, 2)  # not kept yet
        pos[:, k], act[:, k] = new_pos, new_act
        assert value == swarm_violations(pos, act, 1500.0, 5000.0, 2), trial
        if trial % 2:  # kept
            count.keep(state)
        else:  # dropped: the swarm goes back
            pos, act = count.pos.copy(), count.act.copy()
        assert count.value == swarm_violations(pos, act, 1500.0, 5000.0, 2), trial


def _leg_samples_numpy(starts, ends, grid: Grid, w: float):
    """The numpy formulation the compiled ``leg_samples`` keeps bit for bit."""
    d = ends - starts
    length = np.hypot(d[:, 0], d[:, 1])
    m = np.maximum(1, np.ceil(4.0 * length / grid.cell_m)).astype(np.int64)
    leg = np.repeat(np.arange(len(starts)), m)
    first = np.cumsum(m) - m
    t = (np.arange(int(m.sum())) - first[leg] + 0.5) / m[leg]
    xy = starts[leg] + t[:, None] * d[leg]
    ox, oy = grid.origin_m
    col = np.floor((xy[:, 0] - ox) / grid.cell_m).astype(np.int64)
    row = np.floor((xy[:, 1] - oy) / grid.cell_m).astype(np.int64)
    ok = (col >= 0) & (col < grid.nx) & (row >= 0) & (row < grid.ny)
    weight = w * length[leg] / m[leg] / grid.cell_area_m2
    return leg[ok], (row * grid.nx + col)[ok], weight[ok]


def test_compiled_leg_samples_equal_the_numpy_formulation_bit_for_bit():
    """Legs inside, across and outside the map, zero-length and along cell edges: the same
    legs, cells and coverages, exactly (the refinement's plans depend on every bit)."""
    sc = load_scenario("paper_6_2")
    grid = Grid.from_config(sc.map)
    rng = np.random.default_rng(7)
    x0, y0 = grid.origin_m
    span = np.array([grid.nx, grid.ny]) * grid.cell_m
    starts = np.array([x0, y0]) + rng.uniform(-0.2, 1.2, (400, 2)) * span
    ends = starts + rng.normal(0.0, 30_000.0, (400, 2))
    ends[:20] = starts[:20]  # zero length
    starts[20:40, 1] = ends[20:40, 1] = y0 + 3 * grid.cell_m  # along a row edge
    got = leg_samples(starts, ends, grid, 5000.0)
    want = _leg_samples_numpy(starts, ends, grid, 5000.0)
    assert got[0].size > 1000 and got[0].size < 400 * 40  # some samples fall outside
    for a, b in zip(got, want, strict=True):
        assert a.dtype == b.dtype
        np.testing.assert_array_equal(a, b)
    empty = leg_samples(np.zeros((0, 2)), np.zeros((0, 2)), grid, 5000.0)
    assert all(e.size == 0 for e in empty)
