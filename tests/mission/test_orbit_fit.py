"""Plans leave time for the climb spiral and the descent orbit (issue 24, i24-orbitfit).

The scenario is test_final_glide's valley -> bowl plan, with a ring of 3,100 m high ground 6-8 km
round ``bowl`` in the scenario's own elevation grid, so that the planner (which plans each
route to the full 0.85 T in 2-D) meets the descent orbit at planning time: before, ``plan``
refused it ("... min missing for the orbits"); now the UAV's last waypoints are dropped until
flight + orbits fit, and the plan's POS is scored again.
"""

from __future__ import annotations

import numpy as np
import pytest

from poc_env.agents.mission.export import export_plan
from poc_env.agents.mission.plan import load_plan, write_plan
from poc_env.agents.mission.terrain import orbit_time_s, plan_profiles
from poc_env.agents.planning.allocation import sampled_sweep
from poc_env.agents.planning.planner import make_plan
from poc_env.agents.testing.terrain import VALLEY_M, valley_to_bowl
from poc_env.config import load_scenario
from poc_env.theory.probability_map import Grid, build_prior


def _scenario(ring_m: float | None):
    """valley -> bowl, 2 UAVs; with ``ring_m`` a ring of that height 6-8 km round bowl."""
    return load_scenario(valley_to_bowl(ring_m))


@pytest.fixture(scope="module")
def plans():
    """The flat valley's plan and the ring's (allocation, 2 UAVs)."""
    flat = make_plan(_scenario(None), planner="allocation", uavs=2, refine=0)
    ring = make_plan(_scenario(VALLEY_M + 2500.0), planner="allocation", uavs=2, refine=0)
    return flat, ring


def test_a_route_that_needs_a_descent_orbit_is_trimmed_to_fit(tmp_path, plans):
    """The flat plan flies to the full 0.85 T (an orbit would not fit); with the ring the UAVs'
    descent orbits are charged, their routes cut until flight + orbits <= 0.85 T, the plan's POS
    the sampled sweep's of the routes kept, and every format exports it."""
    flat, ring = plans
    sc = _scenario(VALLEY_M + 2500.0)
    usable = sc.uav.usable_endurance_s
    assert "orbit_fit" not in flat
    profs = plan_profiles(ring)
    assert profs is not None and any(p.descent is not None for p in profs)
    trimmed = [int(i) for i in ring["orbit_fit"]["uavs"]]
    assert trimmed
    for u, p, f in zip(ring["uavs"], profs, flat["uavs"]):
        assert u["flight_time_s"] + orbit_time_s(p) <= usable + 1e-6
        if u["id"] in trimmed:  # planned to the full 0.85 T: the orbit did not fit before
            assert f["flight_time_s"] + orbit_time_s(p) > usable
            n = len(u["waypoints_m"])
            assert u["waypoints_m"][:-1] == f["waypoints_m"][: n - 1]  # the route's start kept
            share = ring["orbit_fit"]["uavs"][str(u["id"])]["last_leg_kept"]
            assert 0.0 < share < 1.0  # and the last leg flown part of the way
            a, q = np.asarray(f["waypoints_m"][n - 2]), np.asarray(f["waypoints_m"][n - 1])
            assert u["waypoints_m"][-1] == pytest.approx((a + share * (q - a)).tolist())
    # POS_C of the routes kept, by the allocation's scorer, below the untrimmed plan's
    grid = Grid.from_config(sc.map)
    pos, _ = sampled_sweep(
        sc, grid, build_prior(sc.map),
        [[u["takeoff_m"], *u["waypoints_m"], u["landing_m"]] for u in ring["uavs"]],
    )  # fmt: skip
    assert ring["posc"] == pytest.approx(sum(pos), abs=1e-12)
    assert [u["pos"] for u in ring["uavs"]] == pytest.approx(pos, abs=1e-12)
    assert ring["posc"] < ring["orbit_fit"]["posc_before"]
    write_plan(ring, tmp_path / "plan.json")
    assert "orbit_fit" in load_plan(tmp_path / "plan.json")
    for fmt in ("qgc", "kml", "geojson", "html"):
        export_plan(tmp_path / "plan.json", fmt, out_dir=tmp_path / fmt)
        assert any((tmp_path / fmt).iterdir())


def test_a_flight_already_over_is_not_blamed_on_the_orbits(plans):
    """A UAV whose flight alone is beyond 0.85 T is left to the over-endurance check (marked
    infeasible, refused by the export unless --allow-infeasible), not refused for its orbits."""
    _, ring = plans
    usable = _scenario(None).uav.usable_endurance_s
    uavs = [dict(u) for u in ring["uavs"]]
    uavs[0]["flight_time_s"] = usable + 600.0
    uavs[0]["feasible"] = False
    profs = plan_profiles({**ring, "uavs": uavs})
    assert profs is not None and orbit_time_s(profs[0]) > 0
