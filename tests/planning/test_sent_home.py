"""i24-smallfix, F1 (results/audit/dayaudit/README.md): no UAV is sent for nothing, and a tie
on POS_C keeps the plan that flies least (docs/PLANNER.md, "Nothing to find")."""

from __future__ import annotations

import numpy as np
import pytest

from poc_env.agents.planning.allocation import NOTHING, make_allocation_plan, sampled_sweep
from poc_env.agents.planning.options import PlanOptions
from poc_env.config import load_scenario
from poc_env.theory.probability_map import Grid

#: the audit's one-sighting map (raw/one.py's sone.yaml without its DEM and zones): four fields
#: round a 150 x 155 km area, the two North UAVs first in the fleet, all the mass in one cell
#: 16 km from the South field. Before the fix the plan sent a North UAV 1.5 h (POS 1.0) and the
#: other North UAV 1.5 h for 0.000.
ONE_SIGHTING = {
    "name": "one_sighting",
    "map": {
        "width_km": 150.0,
        "height_km": 155.0,
        "cell_km": 5.0,
        "prior": {
            "kind": "gaussian_mixture",
            "components": [{"mean_km": [72.5, 2.5], "sigma_km": [1, 1], "weight": 1.0}],
        },
    },
    "airfields": [
        {"name": "North", "position_km": [74.5, 166.2]},
        {"name": "South", "position_km": [74.5, -13.8]},
        {"name": "West", "position_km": [-15.5, 76.3]},
        {"name": "East", "position_km": [164.5, 76.2]},
    ],
    "fleet": [
        {"takeoff": "North", "count": 2},
        {"takeoff": "South", "count": 2},
        {"takeoff": "West", "count": 1},
        {"takeoff": "East", "count": 1},
    ],
    "comms": {"range_km": 400},
    "sensor": {"law": "inverse_cube", "sweep_width_km": 5},
    "uav": {"cruise_speed_kmh": 220, "endurance_h": 5, "search_speed_kmh": 180},
}


@pytest.mark.parametrize(
    ("scenario", "cell", "field"),
    [
        (ONE_SIGHTING, (0, 14), "South"),  # the tie: a North UAV alone finds it too
        ("paper_6_2", (1, 24), "B"),  # field A's UAVs first; B's two found 0.000 beside A's
    ],
)
def test_every_uav_flown_adds_something_and_the_nearer_field_flies(scenario, cell, field):
    sc = load_scenario(scenario)
    grid = Grid.from_config(sc.map)
    prior = np.zeros(grid.shape)
    prior[cell] = 1.0
    plan = make_allocation_plan(sc, prior=prior)
    assert plan["posc"] >= 1.0 - 2 * NOTHING  # the sighting is found (eq. 14 sampled)
    paths = [
        [u["takeoff_m"], *u["waypoints_m"], u["landing_m"]] if u["waypoints_m"] else []
        for u in plan["uavs"]
    ]
    flying = [k for k, p in enumerate(paths) if p]
    for k in flying:  # (a) each route flown adds at least NOTHING of the mass
        without = [[] if j == k else p for j, p in enumerate(paths)]
        assert plan["posc"] - sum(sampled_sweep(sc, grid, prior, without)[0]) >= NOTHING, k
    # (b) on a tie on POS_C the least flying is kept: the field next to the sighting flies
    names = [f.takeoff for f in sc.fleet for _ in range(f.count)]
    assert flying and {names[k] for k in flying} == {field}, [names[k] for k in flying]


def test_nothing_zero_flies_every_route_as_before():
    """``PlanOptions(nothing=0)`` turns both off: on the ``paper_6_2`` one-sighting case the
    plan flies UAVs that add nothing, as main did (UAV 1 from A 1.12 h, two B UAVs for 0.000)."""
    sc = load_scenario("paper_6_2")
    grid = Grid.from_config(sc.map)
    prior = np.zeros(grid.shape)
    prior[1, 24] = 1.0
    plan = make_allocation_plan(sc, prior=prior, options=PlanOptions(nothing=0.0))
    assert sum(bool(u["waypoints_m"]) and u["pos"] == 0.0 for u in plan["uavs"]) >= 1


def test_the_summary_names_the_uavs_that_stay_home_and_why():
    """i24-dayaudit2: ``plan``'s and ``replan``'s table printed an idle UAV as a row of 0.00
    and ``ok yes``; the summary now names the UAVs kept home and F1's rule, and says nothing
    of it when every UAV flies (nor when none does: the plan's ``reason`` says why)."""
    from poc_env.agents.planning.planner import home_note, plan_table

    sc = load_scenario("paper_6_2")
    grid = Grid.from_config(sc.map)
    prior = np.zeros(grid.shape)
    prior[1, 24] = 1.0
    plan = make_allocation_plan(sc, prior=prior)
    home = [u["id"] for u in plan["uavs"] if not u["waypoints_m"]]
    assert 0 < len(home) < len(plan["uavs"])
    (line,) = [x for x in plan_table(plan).splitlines() if x.startswith("stay home:")]
    named = line.split(": ")[1].split(" (")[0].removeprefix("UAVs ").removeprefix("UAV ")
    assert [int(i) for i in named.split(", ")] == home
    assert f"({len(home)} of {len(plan['uavs'])}" in line and "PlanOptions.nothing" in line
    flying = {**plan, "uavs": [u for u in plan["uavs"] if u["waypoints_m"]]}
    assert home_note(flying) is None and "stay home" not in plan_table(flying)
    idle = {**plan, "uavs": [{**u, "waypoints_m": []} for u in plan["uavs"]]}
    assert home_note(idle) is None
