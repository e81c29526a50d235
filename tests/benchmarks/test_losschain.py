"""The loss chain from the rule-aware bound to the flown POS
(:mod:`poc_env.agents.benchmarks.losschain`)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import erf

from poc_env.agents.benchmarks.losschain import (
    LINKS,
    VALUES,
    coincident_share,
    footprint_optimum,
    ideal_tracks,
    loss_chain,
    quantised,
    segments_pos,
    time_budget,
)
from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.flight_rules import path_coverage
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.theory.bound import physical_optimum
from poc_env.theory.probability_map import Grid, build_prior
from poc_env.theory.search_theory import pod_from_coverage


@pytest.fixture(scope="module")
def paper():
    sc = load_scenario("paper_6_2")
    return sc, Grid.from_config(sc.map)


def test_ideal_tracks_lay_each_cells_effort_inside_it(paper):
    _, grid = paper
    w = 3000.0  # not the cell side, so that C c / W and C W / c differ
    rng = np.random.default_rng(3)
    cov = rng.uniform(0, 2.5, grid.shape) * (rng.uniform(size=grid.shape) < 0.4)
    a, b = ideal_tracks(cov, grid, w, phase=0.3)
    # every segment in one cell, and W x its length there is C_j a_j (eq. 10 per cell)
    c = grid.cell_m
    ox, oy = grid.origin_m
    col = np.floor((a[:, 0] - ox) / c).astype(int)
    assert np.array_equal(col, np.floor((b[:, 0] - ox - 1e-6) / c).astype(int))
    row = np.floor((a[:, 1] - oy) / c).astype(int)
    got = np.zeros(grid.shape)
    np.add.at(got, (row, col), w * np.hypot(*(b - a).T) / grid.cell_area_m2)
    np.testing.assert_allclose(got, cov, rtol=1e-12, atol=1e-12)
    with pytest.raises(ConfigError, match="phase"):
        ideal_tracks(cov, grid, w, phase=1.0)
    with pytest.raises(ConfigError, match="coverage"):
        ideal_tracks(-cov - 1, grid, w)


def test_ideal_tracks_give_eq10_away_from_the_edges(paper):
    """Uniform coverage C everywhere: cells farther than the cut-off from the map's edge find
    erf(sqrt(pi)/2 C) of their mass (parallel tracks W / C apart, eq. 10), within the sampling's
    2 %."""
    sc, grid = paper
    prior = np.full(grid.shape, 1.0 / grid.nx / grid.ny)
    inner = np.zeros(grid.shape, dtype=bool)
    inner[5:-5, 5:-5] = True  # 25 km from the edges (cut-off 20 km)
    for level in (1.0, 2.0):  # one line per cell, two evenly spaced
        want = float(erf(np.sqrt(np.pi) / 2 * level))
        cov = np.full(grid.shape, level)
        for ph in (0.125, 0.625):
            segs = ideal_tracks(cov, grid, sc.sensor.sweep_width_m, ph)
            _, found = segments_pos(sc, grid, prior, *segs)
            pod = found[inner] / prior[inner]
            assert abs(pod.mean() - want) < 0.02, (level, ph, pod.mean())


def test_footprint_optimum_is_the_water_filling(paper):
    sc, grid = paper
    prior = build_prior(sc.map)
    area = grid.cell_area_m2
    rng = np.random.default_rng(0)
    # one UAV whose footprint is every cell: the plain allocation bound of its effort
    start = rng.uniform(0.1, 1.0, grid.shape)
    val, _ = footprint_optimum(prior, area, [start])
    best = physical_optimum(prior, area, float(start.sum() * area))
    assert val == pytest.approx(best.pos, abs=1e-9)
    # two UAVs on the two halves of the map: the sum of the halves' bounds
    left = np.zeros(grid.shape)
    left[:, : grid.nx // 2] = 0.5
    right = np.zeros(grid.shape)
    right[:, grid.nx // 2 :] = 0.2
    val2, _ = footprint_optimum(prior, area, [left, right])
    half = grid.nx // 2
    want = (
        physical_optimum(prior[:, :half], area, float(left.sum() * area)).pos
        + physical_optimum(prior[:, half:], area, float(right.sum() * area)).pos
    )
    assert val2 == pytest.approx(want, abs=1e-9)
    # two UAVs sharing every cell: the plain bound of their summed effort
    val3, _ = footprint_optimum(prior, area, [start, 0.5 * start])
    assert val3 == pytest.approx(
        physical_optimum(prior, area, float(1.5 * start.sum() * area)).pos, abs=1e-9
    )
    # never below its start (the plan's own spread is feasible)
    own = float(np.sum(prior * pod_from_coverage(left + right)))
    assert val2 >= own


def test_quantised_keeps_the_effort_with_few_spacings():
    rng = np.random.default_rng(1)
    c = rng.uniform(0, 2, (12, 9)) * (rng.uniform(size=(12, 9)) < 0.7)
    for k in (1, 2, 3):
        q = quantised(c, k)
        assert q.sum() == pytest.approx(c.sum())
        assert len(np.unique(q[q > 0])) <= k
        assert np.array_equal(q > 0, c > 0)
    two = np.where(c > 1, 1.5, np.where(c > 0, 0.25, 0.0))  # two spacings already
    np.testing.assert_allclose(quantised(two, 2), two)


def test_coincident_share_counts_tracks_on_top_of_each_other(paper):
    _, grid = paper
    a = np.array([[10e3, 20e3], [150e3, 20e3], [150e3, 30e3], [10e3, 30e3]])
    assert coincident_share([a, a.copy()], grid) == pytest.approx(1.0)
    assert coincident_share([a, a + np.array([0, 60e3])], grid) == 0.0
    half = coincident_share([a, a[:2]], grid)  # the second flies the first's first line
    assert 0.3 < half < 0.7


def test_the_chain_adds_up_to_the_bound_minus_the_flown_pos():
    """On `small`'s allocation plan: every value computed, the links telescope to bound - flown,
    the relaxation's values fall in order, the planned value is the plan's own ``posc`` and the
    grading link (the plan is one of the footprint optimum's spreads) is never negative."""
    sc = load_scenario("small")
    grid = Grid.from_config(sc.map)
    prior = build_prior(sc.map)
    plan = make_allocation_plan(sc, prior=prior)
    flown = plan["posc"] - 0.01  # stands in for a flight
    ch = loss_chain(sc, prior, plan, flown)
    v, links = ch["values"], ch["links"]
    assert list(v) == list(VALUES) and list(links) == list(LINKS)
    assert sum(links.values()) == pytest.approx(v["bound"] - flown, abs=1e-12)
    assert v["bound"] >= v["bound_nospill"] >= v["plan_effort"] > 0
    assert links["grading"] >= -1e-12
    assert v["planned"] == pytest.approx(plan["posc"], abs=1e-12)
    assert v["flown"] == flown
    paths = [
        np.vstack([u["takeoff_m"], np.reshape(u["waypoints_m"], (-1, 2)), u["landing_m"]])
        for u in plan["uavs"]
        if u["waypoints_m"]
    ]
    cov = sum(path_coverage(p, grid, sc.sensor.sweep_width_m) for p in paths)
    assert v["cell_model"] == pytest.approx(float(np.sum(prior * pod_from_coverage(cov))))
    assert ch["side"]["effort_share"] == pytest.approx(
        float(cov.sum()) * grid.cell_area_m2 / ch["side"]["bound_effort_m2"]
    )
    for link in ("sensor_law", "line_geometry"):  # split per cell, exactly
        parts = [ch["side"][f"{link}_{p}"] for p in ("shared", "single", "none")]
        assert sum(parts) == pytest.approx(links[link.replace("_", " ")], abs=1e-12)
    tb = time_budget(sc, plan)
    parts = [tb[k] for k in ("in_map", "outside", "turns", "unused")]
    assert min(parts) >= -1e-9 and sum(parts) == pytest.approx(tb["total"])
    assert tb["total"] == pytest.approx(len(plan["uavs"]) * sc.uav.usable_endurance_s)
    # without a flight the planned POS stands in
    assert loss_chain(sc, prior, plan)["links"]["flying"] == 0.0
    with pytest.raises(ConfigError, match="prior"):
        loss_chain(sc, prior[:-1], plan)
