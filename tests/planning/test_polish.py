"""The polish: a local search on a plan's waypoints scored by the environment's sensor model."""

import dataclasses

import numpy as np
import pytest

from poc_env.agents.planning.allocation import make_allocation_plan, sampled_sweep
from poc_env.agents.planning.flight_rules import plan_speeds, reserve_s
from poc_env.agents.planning.options import PlanOptions
from poc_env.agents.planning.polish import Exposure, polish_for
from poc_env.agents.planning.refine import route_fits
from poc_env.agents.testing.routes import assert_flyable_inside
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.sim.core import takeoff_heading
from poc_env.theory.probability_map import Grid, build_prior


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


@pytest.mark.parametrize("law", ["inverse_cube", "exponential", "definite_range"])
def test_incremental_score_equals_sampled_sweep_after_a_polish(law):
    """The exposure kept move by move gives the environment's own sweep of the polished
    routes (rel. 1e-9), under each detection law, before and after moves are kept."""
    sc = load_scenario("small", overrides={"sensor.law": law})
    prior = build_prior(sc.map)
    routes = [u["waypoints_m"] for u in make_allocation_plan(sc)["uavs"]]
    _, before, _ = _polish(sc, routes, prior, passes=0)
    assert before == pytest.approx(_sampled(sc, routes, prior), rel=1e-9)
    out, value, stats = _polish(sc, routes, prior, passes=2)
    assert stats["moves"] > 0 and out != routes
    assert value == pytest.approx(_sampled(sc, out, prior), rel=1e-9)


def test_polish_never_lowers_planned_pos_and_keeps_routes_flyable():
    """On a random prior of paper_6_2's: the planned POS does not drop, every route fits
    eq. 17-18 (route_fits) and every waypoint lies inside the map."""
    from poc_env.agents.experiments.evaluate import episode_prior

    sc = load_scenario("paper_6_2")
    prior = episode_prior(sc, 7)
    grid, takeoff, landing = _setup(sc)
    routes = [u["waypoints_m"] for u in make_allocation_plan(sc, prior=prior)["uavs"]]
    out, value, stats = _polish(sc, routes, prior, passes=1)
    assert stats["moves"] > 0
    assert value > _sampled(sc, routes, prior) + 1e-4
    assert_flyable_inside(sc, grid, takeoff, landing, out, routes)


def test_a_leg_shift_moves_coincident_lines_apart():
    """Two UAVs fly the same line over a uniform patch: shifting one line sideways (both its
    ends by the same offset) is the move that pays, and the polish finds it with only shifts
    allowed; the lines end up parallel and at least a sweep width apart."""
    sc = load_scenario("small")
    sc = sc.with_uavs(2)
    grid = _setup(sc)[0]
    prior = np.ones(grid.shape) / grid.shape[0] / grid.shape[1]
    line = [[5000.0, 20000.0], [35000.0, 20000.0]]
    routes = [list(map(list, line)), list(map(list, line))]
    out, value, stats = _polish(sc, routes, prior, passes=2, airspace=False, moves=("shift",))
    assert stats["moves"] > 0 and value > _sampled(sc, routes, prior)
    a, b = np.asarray(out[0]), np.asarray(out[1])
    assert a.shape == b.shape == (2, 2)
    for r in (a, b):  # still lines along x: both ends moved alike
        assert r[0, 1] == pytest.approx(r[1, 1])
    assert abs(a[0, 1] - b[0, 1]) >= sc.sensor.sweep_width_m - 1e-6


def _exposure_with_legs(seed=3):
    """The swarm's exposure on ``small`` with a random prior and 5 random legs: (exposure,
    the legs' points, the generator, W)."""
    sc = load_scenario("small")
    grid, *_ = _setup(sc)
    rng = np.random.default_rng(seed)
    prior = rng.random(grid.shape)
    s = sc.sensor.samples_per_cell
    w = sc.sensor.sweep_width_m
    ex = Exposure(grid, s, w, sc.sensor.law, sc.sensor.cutoff_sweep_widths * w,
                  grid.refine(prior, s))  # fmt: skip
    pts = rng.uniform(0, 40000, size=(6, 2))
    ex.add(pts[:-1], pts[1:])
    return ex, pts, rng, w


def test_exposure_gain_equals_the_score_difference():
    """One candidate's gain (exposure_gains) equals the change of the full score when the
    legs are swapped in place."""
    ex, pts, _, _ = _exposure_with_legs()
    v0 = ex.pos()
    old = pts[1:4]
    new = np.array([pts[1], [20000.0, 21000.0], [9000.0, 30000.0], pts[3]])
    gain = ex.gains(old[:-1], old[1:], new[:-1], new[1:], [0, 3])[0]
    ex.add(old[:-1], old[1:], -1.0)
    ex.add(new[:-1], new[1:], 1.0)
    assert gain != 0.0
    assert gain == pytest.approx(ex.pos() - v0, rel=1e-9, abs=1e-13)


def test_default_options_leave_plans_unchanged_and_polish_is_recorded():
    """polish = 0 (the default) plans what the planner planned before (no polish call at all:
    the option's two code paths give the same routes); polish > 0 never plans less POS and
    records its passes and moves."""
    sc = load_scenario("small")
    base = make_allocation_plan(sc)
    same = make_allocation_plan(sc, options=PlanOptions(polish=0))
    assert [u["waypoints_m"] for u in same["uavs"]] == [u["waypoints_m"] for u in base["uavs"]]
    assert same["posc"] == base["posc"] and "polish" not in base["optimizer"]["settings"]
    pol = make_allocation_plan(sc, options=PlanOptions(polish=2))
    assert pol["posc"] > base["posc"]
    rec = pol["optimizer"]["settings"]
    assert rec["polish"]["moves"] > 0 and rec["options"] == {"polish": 2}
    assert pol["posc"] == pytest.approx(_sampled(sc, [u["waypoints_m"] for u in pol["uavs"]],
                                                 build_prior(sc.map)), rel=1e-12)  # fmt: skip


@pytest.mark.parametrize(
    ("change", "field"),
    [({"polish": -1}, "options.polish"), ({"polish": 1.5}, "options.polish"),
     ({"polish_radii": ()}, "options.polish_radii"),
     ({"polish_radii": (0.5, -1.0)}, "options.polish_radii"),
     ({"polish_starts": 0}, "options.polish_starts"),
     ({"polish_max_cells": -1}, "options.polish_max_cells"),
     ({"polish_max_cells": 8.5}, "options.polish_max_cells")],
)  # fmt: skip
def test_polish_options_are_checked(change, field):
    with pytest.raises(ConfigError, match=field.replace(".", r"\.")):
        dataclasses.replace(PlanOptions(), **change)


def test_polish_arguments_are_checked():
    sc = load_scenario("small")
    prior = build_prior(sc.map)
    with pytest.raises(ConfigError, match="moves"):
        _polish(sc, [[], [], []], prior, moves=("jump",))
    with pytest.raises(ConfigError, match="passes"):
        _polish(sc, [[], [], []], prior, passes=-1)
    with pytest.raises(ConfigError, match="radii"):
        _polish(sc, [[], [], []], prior, radii=())


def test_the_size_rule_skips_the_polish_on_larger_maps_only():
    """``polish_max_cells`` (i24-fastpolish): on a map of more cells a side than it allows the
    plan is the unpolished one and the settings say why; at its size the polish runs (0: any
    size). ``small`` has 8 x 8 cells."""
    sc = load_scenario("small")
    base = make_allocation_plan(sc)
    big = make_allocation_plan(sc, options=PlanOptions(polish=1, polish_max_cells=7))
    assert [u["waypoints_m"] for u in big["uavs"]] == [u["waypoints_m"] for u in base["uavs"]]
    assert big["optimizer"]["settings"]["polish"]["skipped"] == "map larger than polish_max_cells"
    assert big["posc"] == base["posc"]
    for limit in (8, 0):
        fits = make_allocation_plan(sc, options=PlanOptions(polish=1, polish_max_cells=limit))
        assert fits["optimizer"]["settings"]["polish"]["moves"] > 0, limit
        assert "skipped" not in fits["optimizer"]["settings"]["polish"]
        assert fits["posc"] > base["posc"]


def test_standard_effort_polishes_the_default_plan():
    """The ``standard`` effort level (i24-fastpolish) is the default plan polished: never less
    planned POS than the default's, the same start, the polish recorded; and the policy
    ``allocation_plan_standard`` plans with it."""
    from poc_env.agents.experiments.evaluate import episode_prior
    from poc_env.agents.policies.registry import make_policy

    sc = load_scenario("paper_6_2")
    prior = episode_prior(sc, 2)
    base = make_allocation_plan(sc, prior=prior)
    std = make_allocation_plan(sc, prior=prior, options=PlanOptions.preset("standard"))
    assert std["posc"] > base["posc"]
    assert std["start"] == base["start"]
    assert std["optimizer"]["settings"]["polish"]["moves"] > 0
    pol = make_policy("allocation_plan_standard")
    assert pol.options == PlanOptions.preset("standard") and pol.name == "allocation_plan_standard"


def test_polishing_more_starts_never_plans_less():
    """``polish_starts`` polishes the next best start too and keeps the best polished plan:
    never less planned POS than polishing the chosen plan alone; the settings say how many
    plans were polished."""
    from poc_env.agents.experiments.evaluate import episode_prior

    sc = load_scenario("small")
    prior = episode_prior(sc, 3)
    one = make_allocation_plan(sc, prior=prior, options=PlanOptions(polish=1))
    two = make_allocation_plan(sc, prior=prior, options=PlanOptions(polish=1, polish_starts=2))
    assert two["posc"] >= one["posc"] - 1e-12
    assert two["optimizer"]["settings"]["polish"]["plans"] == 2


def _lawnmower(ys, x0=15000.0, x1=25000.0):
    """A lawnmower's waypoints: lines along x at the heights ``ys``, turning at alternate
    ends."""
    pts = []
    for j, y in enumerate(ys):
        a, b = (x0, x1) if j % 2 == 0 else (x1, x0)
        pts += [[a, float(y)], [b, float(y)]]
    return pts


def test_a_grade_move_squeezes_a_lawnmower_onto_a_narrow_band():
    """One UAV sweeps four lines 3 km apart (1.2 W) over mass in one row of cells (y 10-15 km)
    at the first two lines:
    with only grade moves allowed (i24-grade) the polish squeezes the run of lines towards the
    band (every line still along x, the spacing smaller), gains planned POS and keeps the
    route flyable; no other kind of move could keep the lines straight and parallel."""
    from poc_env.agents.planning.polish import KINDS, MOVES

    assert "grade" in KINDS and "grade" not in MOVES  # the default moves are unchanged
    sc = load_scenario("small").with_uavs(1)
    grid, takeoff, landing = _setup(sc)
    prior = np.zeros(grid.shape)
    prior[2, 3:5] = 0.5  # small: 8 x 8 cells of 5 km; row 2 is y 10-15 km
    routes = [_lawnmower([12000.0, 15000.0, 18000.0, 21000.0])]
    path = np.vstack([takeoff[0], routes[0], landing[0]])
    heading = takeoff_heading(grid.bounds, takeoff)
    v = plan_speeds(sc)
    fits = (v, sc.uav.max_turn_rate_rad_s, sc.uav.usable_endurance_s, reserve_s(sc))
    assert route_fits(path, *fits, heading[0])
    out, value, stats = _polish(sc, routes, prior, passes=3, airspace=False, moves=("grade",))
    assert stats["moves"] > 0 and value > _sampled(sc, routes, prior) + 1e-3
    assert value == pytest.approx(_sampled(sc, out, prior), rel=1e-9)
    r = np.asarray(out[0])
    assert r.shape == (8, 2)
    assert np.allclose(r[0::2, 1], r[1::2, 1])  # lines along x still
    assert np.ptp(r[:, 1]) < 9000.0 - 1e-6  # squeezed: the run spans less than 3 x 3 km
    assert route_fits(np.vstack([takeoff[0], r, landing[0]]), *fits, heading[0])
    x0, y0, x1, y1 = grid.bounds
    assert np.all((r >= [x0, y0]) & (r <= [x1, y1]))


def test_grade_moves_never_lower_planned_pos_and_keep_routes_flyable():
    """Grade moves alone, then all kinds with grade, on a random prior of small's (the
    airspace check on): the planned POS rises, the score is the environment's sweep of the
    routes, every route fits eq. 17-18 and every waypoint the polish placed lies inside the
    map."""
    from poc_env.agents.experiments.evaluate import episode_prior
    from poc_env.agents.planning.polish import KINDS

    sc = load_scenario("small")
    prior = episode_prior(sc, 7)
    grid, takeoff, landing = _setup(sc)
    routes = [u["waypoints_m"] for u in make_allocation_plan(sc, prior=prior)["uavs"]]
    before = _sampled(sc, routes, prior)
    only, v_only, s_only = _polish(sc, routes, prior, passes=2, moves=("grade",))
    assert s_only["moves"] > 0 and v_only > before + 1e-4  # grade moves alone pay
    out, value, _ = _polish(sc, routes, prior, passes=2, moves=KINDS)
    assert value > before and value == pytest.approx(_sampled(sc, out, prior), rel=1e-9)
    assert v_only == pytest.approx(_sampled(sc, only, prior), rel=1e-9)
    assert_flyable_inside(sc, grid, takeoff, landing, (*only, *out), routes)


def test_polish_grade_option_is_checked_and_reaches_the_polish():
    """``polish_grade`` is a flag (ConfigError naming it otherwise); set, the plan's polish
    tries the grade moves (a different plan from the one without them on small)."""
    with pytest.raises(ConfigError, match=r"options\.polish_grade"):
        PlanOptions(polish_grade=1)  # type: ignore[arg-type]
    sc = load_scenario("small")
    a = make_allocation_plan(sc, options=PlanOptions(polish=2))
    b = make_allocation_plan(sc, options=PlanOptions(polish=2, polish_grade=True))
    assert b["optimizer"]["settings"]["options"]["polish_grade"] is True
    assert [u["waypoints_m"] for u in a["uavs"]] != [u["waypoints_m"] for u in b["uavs"]]


def test_a_block_move_carries_a_run_of_lines_onto_the_mass():
    """One UAV sweeps three lines 5 km apart (W) along x at x 10-20 km, y 10-20 km; the mass
    lies in the cells at x 20-35 km, y 15-30 km (up and to the right of the run): with only
    block moves allowed (i24-lines) the polish carries the run towards the mass (across the
    lines and along them), gains planned POS (the score the environment's sweep), and keeps
    the route flyable and inside the map."""
    from poc_env.agents.planning.polish import ALL_KINDS, KINDS

    assert "block" in ALL_KINDS and "block" not in KINDS  # grade's kinds (thorough) unchanged
    sc = load_scenario("small").with_uavs(1)
    grid, takeoff, landing = _setup(sc)
    prior = np.zeros(grid.shape)
    prior[3:6, 4:7] = 1.0 / 9.0  # small: 8 x 8 cells of 5 km; rows y 15-30, columns x 20-35
    routes = [_lawnmower([10000.0, 15000.0, 20000.0], x0=10000.0, x1=20000.0)]
    before = _sampled(sc, routes, prior)
    out, value, stats = _polish(sc, routes, prior, passes=3, airspace=False, moves=("block",))
    assert stats["moves"] > 0 and value > before + 1e-3
    assert value == pytest.approx(_sampled(sc, out, prior), rel=1e-9)
    r, r0 = np.asarray(out[0]), np.asarray(routes[0])
    assert r.shape == r0.shape  # no waypoint added or taken away: the run translated
    assert r[:, 0].mean() > r0[:, 0].mean() + 1000.0 and r[:, 1].mean() > r0[:, 1].mean() + 1000.0
    v = plan_speeds(sc)
    heading = takeoff_heading(grid.bounds, takeoff)
    fits = (v, sc.uav.max_turn_rate_rad_s, sc.uav.usable_endurance_s, reserve_s(sc))
    assert route_fits(np.vstack([takeoff[0], r, landing[0]]), *fits, heading[0])
    x0, y0, x1, y1 = grid.bounds
    assert np.all((r >= [x0, y0]) & (r <= [x1, y1]))


def test_block_moves_never_lower_planned_pos_and_keep_routes_flyable():
    """Every kind of move with the block moves, after a polish without them, on a random prior
    of small's (the airspace check on): the planned POS does not fall (and rises here), the
    score is the environment's sweep of the routes, every route fits eq. 17-18 and every
    waypoint the polish placed lies inside the map."""
    from poc_env.agents.experiments.evaluate import episode_prior
    from poc_env.agents.planning.polish import KINDS

    sc = load_scenario("small")
    prior = episode_prior(sc, 7)
    grid, takeoff, landing = _setup(sc)
    routes = [u["waypoints_m"] for u in make_allocation_plan(sc, prior=prior)["uavs"]]
    first, v_first, _ = _polish(sc, routes, prior, passes=2, moves=KINDS)
    out, value, stats = _polish(sc, first, prior, passes=2, moves=(*KINDS, "block"))
    assert stats["block_moves"] > 0 and value > v_first + 1e-5
    assert value == pytest.approx(_sampled(sc, out, prior), rel=1e-9)
    assert_flyable_inside(sc, grid, takeoff, landing, out, first)


@pytest.mark.parametrize("bad", [-1, 1.5, True, 101])
def test_polish_lines_option_is_checked(bad):
    with pytest.raises(ConfigError, match=r"options\.polish_lines"):
        PlanOptions(polish_lines=bad)


@pytest.mark.parametrize("bad", [(), (0.5, -1.0), (0.5, 9.0), (float("nan"),)])
def test_polish_lines_radii_option_is_checked(bad):
    with pytest.raises(ConfigError, match=r"options\.polish_lines_radii"):
        PlanOptions(polish_lines_radii=bad)


def test_polish_lines_option_reaches_the_plan_and_never_plans_less():
    """``polish_lines`` runs a second polish with the block moves after the polish: on small
    it keeps block moves (recorded in the settings), and the plan never plans less POS than
    the polish alone (the second stage starts from its routes and keeps only gains)."""
    sc = load_scenario("small")
    a = make_allocation_plan(sc, options=PlanOptions(polish=2, polish_grade=True))
    b = make_allocation_plan(sc, options=PlanOptions(polish=2, polish_grade=True, polish_lines=2))
    st = b["optimizer"]["settings"]
    assert st["options"]["polish_lines"] == 2 and st["polish"]["block_moves"] > 0
    assert b["posc"] >= a["posc"] - 1e-12
    assert [u["waypoints_m"] for u in a["uavs"]] != [u["waypoints_m"] for u in b["uavs"]]


def test_polish_lines_radii_reach_the_second_polish():
    """``polish_lines_radii`` are the second polish's radii (not the first's): on small, with
    W/8 added, the second polish keeps other moves than with the default radii, and the first
    polish is the same (so the plan differs only through the second)."""
    sc = load_scenario("small")
    opt = PlanOptions(polish=2, polish_grade=True, polish_lines=1)
    a = make_allocation_plan(sc, options=opt)
    fine = dataclasses.replace(opt, polish_lines_radii=(0.125, 0.25, 0.5, 1.0, 2.0))
    b = make_allocation_plan(sc, options=fine)
    assert [u["waypoints_m"] for u in a["uavs"]] != [u["waypoints_m"] for u in b["uavs"]]
    sa, sb = a["optimizer"]["settings"]["polish"], b["optimizer"]["settings"]["polish"]
    assert sa["moves"] - sa["lines_moves"] == sb["moves"] - sb["lines_moves"]


@pytest.mark.parametrize("bad", [(), (0,), (2, 1.5), (2, True), (17,), [2, 4]])
def test_polish_lines_windows_option_is_checked(bad):
    with pytest.raises(ConfigError, match=r"options\.polish_lines_windows"):
        PlanOptions(polish_lines_windows=bad)


@pytest.mark.parametrize(
    ("field", "bad"),
    [("block_windows", ()), ("block_windows", (2, 0)), ("block_windows", (2.0,)),
     ("block_radii", ()), ("block_radii", (0.5, -1.0)), ("focus", -1), ("focus", 1.5)],
)  # fmt: skip
def test_block_window_arguments_are_checked(field, bad):
    sc = load_scenario("small")
    routes = [u["waypoints_m"] for u in make_allocation_plan(sc)["uavs"]]
    with pytest.raises(ConfigError, match=field):
        _polish(sc, routes, build_prior(sc.map), moves=("move", "block"), **{field: bad})


def test_block_windows_are_the_ones_asked_and_the_trace_sees_every_kept_move():
    """``block_windows`` (i24-cheapolish) are the block moves' windows: traced, the block
    moves of a polish with windows of 2 waypoints are tried on windows of 2 only, those of the
    default on :data:`BLOCK_WINDOWS`; the trace sees as many kept moves as the polish counts
    and does not change its routes; and ``polish_lines_windows`` reaches the planner's second
    polish (its plan is the second polish of those windows replayed)."""
    from poc_env.agents.planning.polish import BLOCK_WINDOWS, KINDS

    sc = load_scenario("small")
    prior = build_prior(sc.map)
    routes = [u["waypoints_m"] for u in make_allocation_plan(sc)["uavs"]]
    kinds = (*KINDS, "block")
    seen: list[tuple] = []
    a = _polish(sc, routes, prior, moves=kinds, block_windows=(2,), trace=lambda *t: seen.append(t))
    assert a[:2] == _polish(sc, routes, prior, moves=kinds, block_windows=(2,))[:2]
    assert {t[4] for t in seen if t[0] == "block"} == {2}
    assert sum(t[6] >= 0 for t in seen) == a[2]["moves"] > 0
    seen.clear()
    _polish(sc, routes, prior, moves=kinds, trace=lambda *t: seen.append(t))
    assert {t[4] for t in seen if t[0] == "block"} == set(BLOCK_WINDOWS)
    opt = PlanOptions(polish_lines=2, polish_grade=True, polish_lines_windows=(2,))
    plan = make_allocation_plan(sc, options=opt)
    assert [u["waypoints_m"] for u in plan["uavs"]] == a[0]


@pytest.mark.parametrize("bad", [(0.5, -1.0), (9.0,), (float("nan"),), [0.5]])
def test_polish_lines_block_radii_option_is_checked(bad):
    with pytest.raises(ConfigError, match=r"options\.polish_lines_block_radii"):
        PlanOptions(polish_lines_block_radii=bad)


def test_block_radii_reach_the_block_moves_only():
    """``block_radii`` (i24-cheapolish) are the block moves' radii: traced, a polish with one
    block radius tries 4 candidates a block window (across and along, both signs) and its
    other moves as many as without it; ``polish_lines_block_radii`` reaches the planner's
    second polish (its plan is that polish replayed)."""
    from poc_env.agents.planning.polish import KINDS

    sc = load_scenario("small")
    prior = build_prior(sc.map)
    routes = [u["waypoints_m"] for u in make_allocation_plan(sc)["uavs"]]
    kinds = (*KINDS, "block")
    seen: list[tuple] = []
    a = _polish(sc, routes, prior, passes=1, moves=kinds, block_radii=(0.25,),
                trace=lambda *t: seen.append(t))  # fmt: skip
    assert {t[5] for t in seen if t[0] == "block"} == {4}
    first = next(t for t in seen if t[0] == "waypoint")  # before any move is kept
    seen.clear()
    _polish(sc, routes, prior, passes=1, moves=kinds, trace=lambda *t: seen.append(t))
    assert first[5] == next(t for t in seen if t[0] == "waypoint")[5]
    assert {t[5] for t in seen if t[0] == "block"} == {16}
    opt = PlanOptions(polish_lines=1, polish_grade=True, polish_lines_block_radii=(0.25,))
    plan = make_allocation_plan(sc, options=opt)
    assert [u["waypoints_m"] for u in plan["uavs"]] == a[0]


def test_focus_tries_window_moves_only_near_the_last_pass_kept_moves():
    """``focus`` (i24-cheapolish): in the second pass of a polish with ``focus=0`` every grade
    and block move is tried at a waypoint that a move kept in the first pass changed (in the
    first pass's numbering), and fewer are tried than without the focus; the first pass is
    the same as without it."""
    from poc_env.agents.planning.polish import KINDS

    sc = load_scenario("small")
    prior = build_prior(sc.map)
    routes = [u["waypoints_m"] for u in make_allocation_plan(sc)["uavs"]]
    kinds = (*KINDS, "block")
    runs = []
    for focus in (0, None):
        seen: list[tuple] = []
        _polish(sc, routes, prior, passes=2, moves=kinds, focus=focus,
                trace=lambda *t, seen=seen: seen.append(t))  # fmt: skip
        runs.append(seen)
    focused, free = runs
    assert [t for t in focused if t[1] == 1] == [t for t in free if t[1] == 1]
    changed: dict[int, list[tuple[int, int]]] = {}
    for _kind, pss, k, i, window, _, kept, _ in focused:
        if pss == 1 and kept >= 0:  # the inner waypoints the kept move changed
            changed.setdefault(k, []).append((i, i + window - 1 if window else i + 1))
    tried = [(k, i) for kind, pss, k, i, *_ in focused if pss == 2 and kind in ("grade", "block")]
    assert tried and all(any(a <= i <= b for a, b in changed.get(k, [])) for k, i in tried)
    n_free = sum(1 for t in free if t[1] == 2 and t[0] in ("grade", "block"))
    assert len(tried) < n_free


def test_screened_gains_score_the_screens_best_exactly():
    """``screened_gains`` (i24-fast2s): without a screen (or with as many places as
    candidates) the exact gains; with ``top`` places, the ``top`` candidates best by the
    shorter cut-off's gains get their exact gains (bit for bit) and every other ``-inf``."""
    from poc_env.agents.planning.polish import screened_gains

    ex, pts, rng, w = _exposure_with_legs()
    old = pts[1:4]
    moved = old[1][None, None] + rng.normal(0.0, 0.5 * w, size=(12, 1, 2))  # the waypoint moved
    cands = np.concatenate(
        [np.broadcast_to(old[0], (12, 1, 2)), moved, np.broadcast_to(old[2], (12, 1, 2))], axis=1
    )
    starts = cands[:, :-1].reshape(-1, 2)
    ends = cands[:, 1:].reshape(-1, 2)
    first = np.arange(13) * 2
    exact = ex.gains(old[:-1], old[1:], starts, ends, first)
    old_a, old_b = old[:-1], old[1:]
    assert np.array_equal(screened_gains(ex, old_a, old_b, starts, ends, first, None, w), exact)
    assert np.array_equal(screened_gains(ex, old_a, old_b, starts, ends, first, 12, w), exact)
    rough = ex.gains(old_a, old_b, starts, ends, first, cutoff_m=w)
    assert not np.array_equal(rough, exact)  # the screen's cut-off changes the scores
    got = screened_gains(ex, old_a, old_b, starts, ends, first, 4, w)
    best = set(np.argsort(-rough, kind="stable")[:4].tolist())
    assert set(np.flatnonzero(np.isfinite(got)).tolist()) == best
    assert all(got[c] == exact[c] for c in best)


def test_a_screened_polish_never_lowers_planned_pos_and_keeps_routes_flyable():
    """A screened polish (``screen``) keeps only moves of exact gain: its planned POS is the
    environment's sweep of its routes and at least the routes' own, the routes fit; it
    differs from the unscreened polish (fewer candidates scored exactly) and with a screen
    at the sensor's own cut-off and room for every candidate it is the unscreened polish."""
    from poc_env.agents.planning.polish import KINDS

    sc = load_scenario("small")
    prior = build_prior(sc.map)
    routes = [u["waypoints_m"] for u in make_allocation_plan(sc)["uavs"]]
    kinds = (*KINDS, "block")
    free = _polish(sc, routes, prior, moves=kinds)
    full = _polish(sc, routes, prior, moves=kinds, screen=10_000,
                   screen_cutoff=sc.sensor.cutoff_sweep_widths)  # fmt: skip
    assert full[:2] == free[:2]
    scr = _polish(sc, routes, prior, moves=kinds, screen=2, screen_cutoff=0.5)
    assert scr[0] != free[0]
    assert scr[1] == pytest.approx(_sampled(sc, scr[0], prior), rel=1e-9)
    assert scr[1] > _sampled(sc, routes, prior)
    speeds = plan_speeds(sc)
    grid, takeoff, landing = _setup(sc)
    heads = takeoff_heading(grid.bounds, takeoff)
    for k, r in enumerate(scr[0]):
        if r:
            path = np.vstack([takeoff[k], r, landing[k]])
            assert route_fits(path, speeds, sc.uav.max_turn_rate_rad_s,
                              sc.uav.usable_endurance_s, reserve_s(sc), heads[k])  # fmt: skip


@pytest.mark.parametrize(
    ("change", "field"),
    [({"polish_screen": -1}, "options.polish_screen"),
     ({"polish_screen": 2.5}, "options.polish_screen"),
     ({"polish_screen_cutoff": 0.0}, "options.polish_screen_cutoff"),
     ({"polish_screen_cutoff": float("nan")}, "options.polish_screen_cutoff")],
)  # fmt: skip
def test_polish_screen_options_are_checked(change, field):
    with pytest.raises(ConfigError, match=field.replace(".", r"\.")):
        dataclasses.replace(PlanOptions(), **change)


def test_polish_screen_arguments_are_checked_and_the_option_reaches_the_polish():
    """``screen``/``screen_cutoff`` are checked (a ``ConfigError`` naming them), and
    ``polish_screen`` reaches the planner's polish (its plan is the screened polish replayed)."""
    sc = load_scenario("small")
    prior = build_prior(sc.map)
    for kw, field in (({"screen": 0}, "screen"), ({"screen": True}, "screen"),
                      ({"screen": 4, "screen_cutoff": -1.0}, "screen_cutoff"),
                      ({"screen": 4, "screen_cutoff": "2"}, "screen_cutoff")):  # fmt: skip
        with pytest.raises(ConfigError, match=field):
            _polish(sc, [[], [], []], prior, **kw)
    routes = [u["waypoints_m"] for u in make_allocation_plan(sc)["uavs"]]
    from poc_env.agents.planning.polish import MOVES

    want = _polish(sc, routes, prior, passes=1, moves=MOVES, screen=2, screen_cutoff=0.5)
    plan = make_allocation_plan(
        sc, options=PlanOptions(polish=1, polish_screen=2, polish_screen_cutoff=0.5)
    )
    assert [u["waypoints_m"] for u in plan["uavs"]] == want[0]
    assert want[0] != _polish(sc, routes, prior, passes=1, moves=MOVES)[0]
