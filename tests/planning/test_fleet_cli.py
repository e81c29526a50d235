"""``poc-env plan --fleet-sizes`` (i24-fleetcli, finding F2 of results/audit/dayaudit): the
allocation plans of several fleet sizes, each planned on the one before (``plan_fleets``), one
plan file per size, one table; bad size lists refused before anything is written.

On ``small`` the default plan of 9 UAVs planned alone finds less than that of 8 (0.8862
against 0.8871): a table of independent plans would fall there. Since i24-chain the chain keeps
the 8 UAVs' routes only where they keep the fill's clearance (1.5 d_s at planned times); on
this small map 17 pairs of them do not, the 9 UAVs' own plan (0.8862) is kept instead of what
is left of them filled, and the table says that it falls."""

import json
import re

import numpy as np
import pytest

from poc_env.cli import fleet_plan_path, main
from poc_env.errors import ConfigError

SIZES = (6, 8, 9)
BASE = ["plan", "--scenario", "small", "--planner", "allocation", "--quiet"]


@pytest.fixture(scope="module")
def fleet_run(tmp_path_factory):
    """One ``plan --fleet-sizes 6,8,9`` on ``small`` (with ``--origin``): its folder and the
    table's rows (UAVs, POS_C, bound, ratio, without a route)."""
    import contextlib
    import io

    folder = tmp_path_factory.mktemp("fleet") / "out"
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        rc = main([*BASE, "--fleet-sizes", ",".join(map(str, SIZES)), "--origin", "45,5",
                   "--out", str(folder / "plan.json")])  # fmt: skip
    assert rc == 0, buf.getvalue()
    rows = [
        line.split()
        for line in buf.getvalue().splitlines()
        if re.match(r"^\s*\d+\s+\d\.\d{4}\s", line)
    ]
    return folder, rows, buf.getvalue()


def test_the_table_says_where_it_falls_and_each_size_has_its_plan_file(fleet_run):
    folder, rows, text = fleet_run
    assert [int(r[0]) for r in rows] == list(SIZES)
    posc = [json.loads((folder / f"plan_n{n}.json").read_text())["posc"] for n in SIZES]
    fell = [str(n) for n, a, b in zip(SIZES[1:], posc[:-1], posc[1:], strict=True) if b < a]
    assert fell == ["9"], text  # the premise (module docstring)
    assert f"POS_C falls at {', '.join(fell)} UAVs: routes of the smaller fleet" in text
    # one file per size, nothing else (no plan.json itself)
    assert sorted(p.name for p in folder.iterdir()) == [f"plan_n{n}.json" for n in SIZES]
    for n, row in zip(SIZES, rows, strict=True):
        plan = json.loads((folder / f"plan_n{n}.json").read_text())
        assert len(plan["uavs"]) == n
        assert f"{plan['posc']:.4f}" == row[1]
        assert f"{plan['bound_rule']:.4f}" == row[2]
        assert sum(1 for u in plan["uavs"] if not u["waypoints_m"]) == int(row[4])
        assert f"wrote {folder / f'plan_n{n}.json'}" in text
    floors = [json.loads((folder / f"plan_n{n}.json").read_text())["optimizer"]["settings"]
              .get("fleet", {}).get("floor_uavs") for n in SIZES]  # fmt: skip
    assert floors == [None, 6, 8]  # each planned on the one before


def test_a_written_plan_exports_and_flies_as_any_plan(fleet_run, tmp_path, fly):
    """The 9-UAV plan: exported to QGC without ``--origin`` (the plan records its crs), one
    mission per UAV with a route; flown by the waypoint follower on the scenario with 9 UAVs,
    every UAV lands."""
    from poc_env.agents.mission.plan import load_plan
    from poc_env.agents.policies.base import PlanPolicy
    from poc_env.config import load_scenario

    folder, _, _ = fleet_run
    path = folder / "plan_n9.json"
    plan = json.loads(path.read_text())
    routed = sum(1 for u in plan["uavs"] if u["waypoints_m"])
    assert main(["export", str(path), "--format", "qgc", "--out", str(tmp_path / "m")]) == 0
    assert len(list((tmp_path / "m").glob("plan_n9_uav*.plan"))) == routed
    loaded = load_plan(path)

    class FilePlan(PlanPolicy):
        def make(self, env, prior, seed):
            return loaded

    flight = fly(load_scenario("small").with_uavs(9), FilePlan(), seed=0)
    assert flight.landed == 9 and flight.nofly_steps == 0
    assert np.isclose(flight.posc, plan["posc"], atol=0.1)  # flown near what it planned


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--fleet-sizes", "8,6"], "fleet_sizes: got '8,6'; allowed: fleet sizes in increasing"),
        (["--fleet-sizes", "6,6"], "fleet_sizes: got '6,6'; allowed: fleet sizes in increasing"),
        (["--fleet-sizes", "0,4"], "fleet_sizes[0]: got 0; allowed: an integer in [1, 64]"),
        (["--fleet-sizes", "4,65"], "fleet_sizes[1]: got 65; allowed: an integer in [1, 64]"),
        (["--fleet-sizes", "4,x"], "fleet_sizes[1]: got 'x'"),
        (["--fleet-sizes", "4,,6"], "fleet_sizes[1]: got ''"),
        (["--fleet-sizes", "4,6", "--uavs", "4"], "uavs: got 4; allowed: either --uavs or"),
        (["--fleet-sizes", "4,6", "--effort", "thorough"], "effort: got 'thorough'"),
        (["--fleet-sizes", "4,6", "--plot", "p.png"], "plot: got"),
        (
            ["--fleet-sizes", "4,6", "--overrides", "fleet=[{takeoff: A, count: 2}]"],
            "fleet_sizes: got '4,6'; allowed: either --fleet-sizes or --overrides fleet",
        ),
    ],
)
def test_a_refused_size_list_writes_nothing(tmp_path, capsys, monkeypatch, extra, message):
    monkeypatch.chdir(tmp_path)
    assert main([*BASE, *extra, "--out", str(tmp_path / "o" / "plan.json")]) == 2
    assert message in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_the_de_planner_is_refused_with_fleet_sizes(tmp_path, capsys):
    args = ["plan", "--scenario", "small", "--fleet-sizes", "4,6", "--out", str(tmp_path / "p")]
    assert main(args) == 2
    assert "planner: got 'de'; allowed: allocation with --fleet-sizes" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_plan_file_names_stay_beside_out_and_never_overwrite_an_input(tmp_path, capsys):
    assert fleet_plan_path("a/plan.json", 12) == fleet_plan_path("a/x.json", 1).parent / (
        "plan_n12.json"
    )
    assert fleet_plan_path("a/plan.v2.json", 6).name == "plan.v2_n6.json"
    assert fleet_plan_path("plan", 6).name == "plan_n6"
    for bad in ("", "/"):  # no file name to derive from
        with pytest.raises(ConfigError, match="out: got"):
            fleet_plan_path(bad, 6)
    # a derived name that is an input file (the scenario YAML here) is refused, before planning
    from poc_env.config import CONFIG_DIR

    scenario = tmp_path / "sc_n4.yaml"
    scenario.write_bytes((CONFIG_DIR / "small.yaml").read_bytes())
    before = scenario.read_bytes()
    args = ["plan", "--scenario", str(scenario), "--planner", "allocation", "--quiet"]
    assert main([*args, "--fleet-sizes", "4", "--out", str(tmp_path / "sc.yaml")]) == 2
    assert "sc_n4.yaml" in capsys.readouterr().err
    assert scenario.read_bytes() == before and sorted(tmp_path.iterdir()) == [scenario]


def test_a_folder_where_a_plan_file_goes_is_refused_before_planning(tmp_path, capsys):
    (tmp_path / "plan_n6.json").mkdir()
    args = [*BASE, "--fleet-sizes", "4,6", "--out", str(tmp_path / "plan.json")]
    assert main(args) == 2
    err = capsys.readouterr()
    assert f"out: got '{tmp_path / 'plan_n6.json'}'" in err.err and "UAVs" not in err.out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan_n6.json"]


def test_each_size_is_said_as_it_is_planned_unless_quiet(tmp_path, capsys):
    """A 500 km map takes minutes a size: a line per size as it is planned, before the
    table (none with ``--quiet``)."""
    args = ["plan", "--scenario", "small", "--planner", "allocation", "--fleet-sizes", "2,3"]
    assert main([*args, "--out", str(tmp_path / "a" / "plan.json")]) == 0
    out = capsys.readouterr().out
    said = [line for line in out.splitlines() if line.startswith("planned ")]
    assert [s.split(":")[0] for s in said] == ["planned 2 UAVs", "planned 3 UAVs"]
    assert out.index("planned 3 UAVs") < out.index("UAVs   POS_C")
    assert main([*args, "--quiet", "--out", str(tmp_path / "b" / "plan.json")]) == 0
    assert not [x for x in capsys.readouterr().out.splitlines() if x.startswith("planned ")]
