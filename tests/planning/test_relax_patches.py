"""The relaxation-patch start of the allocation planner (i24-relax,
:mod:`poc_env.agents.planning.relax_patches`)."""

import numpy as np
import pytest

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.agents.planning.allocation import COVER_CAP, make_allocation_plan
from poc_env.agents.planning.flight_rules import SPEED, plan_speeds, reserve_s
from poc_env.agents.planning.options import PlanOptions
from poc_env.agents.planning.refine import route_fits
from poc_env.agents.planning.relax_patches import (
    dedicated_allocation,
    field_groups,
    relax_routes,
    sectors,
)
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.sim.core import takeoff_heading
from poc_env.theory.bound import cell_distances
from poc_env.theory.probability_map import Grid


def _inputs(name="large_400", seed=5000, **over):
    sc = load_scenario(name, {"map.cell_km": 20, **over} if name == "large_400" else over)
    grid = Grid.from_config(sc.map)
    prior = episode_prior(sc, seed)
    to = np.asarray(sc.takeoff_m, dtype=float).reshape(-1, 2)
    la = np.asarray(sc.landing_m, dtype=float).reshape(-1, 2)
    v = plan_speeds(sc, SPEED)
    tau = cell_distances(grid, to) / v.out + cell_distances(grid, la) / v.home
    return sc, grid, prior, to, la, v, tau


def _relax(sc, grid, prior, to, la, v, tau, eta=0.5):
    u = sc.uav
    return relax_routes(
        prior, grid, sc.sensor.sweep_width_m, sc.sensor.law, v, to, la, tau, eta,
        u.usable_endurance_s, u.max_turn_rate_rad_s, reserve_s(sc),
        takeoff_heading(grid.bounds, to), (3, 4), (1.0, 0.8), PlanOptions(relax_start=True),
    )  # fmt: skip


def test_routes_keep_eq_17_18_stay_in_the_map_and_every_uav_gets_a_patch():
    """Three airfields, 12 UAVs, a random prior: every UAV (each reaches mass) gets a route of
    search lines inside the map, flown whole under eq. 17-18."""
    sc, grid, prior, to, la, v, tau = _inputs()
    routes = _relax(sc, grid, prior, to, la, v, tau)
    heading = takeoff_heading(grid.bounds, to)
    x0, y0, x1, y1 = grid.bounds
    u = sc.uav
    for k, r in enumerate(routes):
        assert len(r) >= 2 and len(r) % 2 == 0, k  # lines: two waypoints each
        arr = np.asarray(r)
        assert np.all((arr[:, 0] >= x0) & (arr[:, 0] <= x1) & (arr[:, 1] >= y0) & (arr[:, 1] <= y1))
        path = np.vstack([to[k], arr, la[k]])
        assert route_fits(
            path, v, u.max_turn_rate_rad_s, u.usable_endurance_s, reserve_s(sc), heading[k]
        ), k


def test_a_uav_that_reaches_no_mass_gets_no_route():
    """Mass only in the map's top rows and an endurance too short for the southern fields:
    their UAVs get nothing, the northern field's UAVs a route each."""
    sc, grid, _, to, la, v, tau = _inputs(**{"uav.endurance_h": 1.5})
    prior = np.zeros(grid.shape)
    prior[-3:, :] = 1.0
    prior /= prior.sum()
    routes = _relax(sc, grid, prior, to, la, v, tau)
    reach = (tau < sc.uav.usable_endurance_s) & (prior > 0)[None]
    can = reach.reshape(len(to), -1).any(axis=1)
    assert can.any() and not can.all()
    assert [bool(r) for r in routes] == can.tolist()


def test_dedicated_allocation_keeps_each_fields_uav_time():
    """Each field's coverage needs at most its UAVs: sum_j a C_fj / (rate (B - t_fj)) <= n_f;
    a field that does not use them all (within the dual's tolerance) has nothing left to gain:
    every cell it reaches is searched at the coverage cap."""
    sc, grid, prior, to, la, v, tau = _inputs()
    groups = field_groups(to, la)
    t_f = np.stack([tau[g[0]] for g in groups])
    rate = 0.5 * sc.sensor.sweep_width_m * v.line
    b = sc.uav.usable_endurance_s
    cov = dedicated_allocation(prior, grid.cell_area_m2, t_f, [len(g) for g in groups], rate, b,
                               sc.sensor.law)  # fmt: skip
    slack = []
    for f, g in enumerate(groups):
        on = cov[f] > 0
        assert np.all(t_f[f][on] < b)
        used = float(np.sum(grid.cell_area_m2 * cov[f][on] / (rate * (b - t_f[f][on]))))
        assert used <= len(g) * (1 + 1e-6)
        if used < 0.99 * len(g):
            slack.append(f)
            reached = (t_f[f] < b) & (prior > 0)
            assert np.all(cov.sum(axis=0)[reached] >= COVER_CAP * (1 - 1e-9))
    assert len(slack) < len(groups)  # the mass outweighs the fleet somewhere
    assert np.all(cov.sum(axis=0) <= COVER_CAP * (1 + 1e-9))


def test_sectors_cut_by_bearing_into_runs_of_equal_time():
    bearing = np.linspace(-1.0, 1.0, 40)
    part = sectors(np.full(40, 100.0), np.full(40, 10.0), bearing[::-1], 4)
    assert sorted(set(part.tolist())) == [0, 1, 2, 3]
    assert np.all(np.diff(part[::-1]) >= 0)  # contiguous in bearing
    assert np.bincount(part).tolist() == [10, 10, 10, 10]


def test_option_puts_the_start_in_the_plan():
    """With the option the relaxation patches are a start, recorded when kept; without it the
    plan never says ``relax``. large_400 at 20 km cells, seed 5000: the patches win there."""
    sc = load_scenario("large_400", {"map.cell_km": 20})
    prior = episode_prior(sc, 5000)
    opt = PlanOptions(greedy_start=False, box_start=False, refine=0)
    import dataclasses

    on = make_allocation_plan(sc, prior=prior, options=dataclasses.replace(opt, relax_start=True))
    off = make_allocation_plan(sc, prior=prior, options=opt)
    assert on["start"] == "relax" and off["start"] == "allocation"
    assert on["posc"] != off["posc"]
    assert on["optimizer"]["settings"]["options"]["relax_start"] is True


@pytest.mark.parametrize(
    ("change", "field"),
    [({"relax_start": 1}, "options.relax_start"),
     ({"relax_scales": (1.0, 1.5)}, "options.relax_scales"),
     ({"relax_scales": ()}, "options.relax_scales"),
     ({"relax_etas": (0.5, 1.2)}, "options.relax_etas")],
)  # fmt: skip
def test_bad_relax_options_name_the_field(change, field):
    with pytest.raises(ConfigError) as err:
        PlanOptions(**change)
    assert err.value.field == field


def test_the_start_goes_around_no_fly_zones():
    """A zone along ``paper_6_2``'s southern edge, in the way out of both airfields: the
    relaxation patches, kept as the start, cross it nowhere (eq. 20: routed around as the
    boxes are)."""
    import shapely

    band = [[[10, 5], [130, 5], [130, 15], [10, 15]]]  # between both airfields and the mass
    sc = load_scenario("paper_6_2", {"map.no_fly_zones_km": band})
    opt = PlanOptions(relax_start=True, box_start=False, greedy_start=False, refine=0)
    plan = make_allocation_plan(sc, options=opt)
    assert plan["start"] == "relax"
    zone = shapely.Polygon(sc.map.no_fly_zones_m[0])
    for u in plan["uavs"]:
        path = shapely.LineString([u["takeoff_m"], *u["waypoints_m"], u["landing_m"]])
        assert not path.intersects(zone)
