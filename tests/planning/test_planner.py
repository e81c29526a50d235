"""`poc-env plan`: schema-1 plan.json, feasible plans inside their rectangles, reproducible."""

import json
from pathlib import Path

import numpy as np
import pytest
from shapely.geometry import Point

from poc_env.agents.mission.export import export_plan
from poc_env.agents.mission.plan import load_plan
from poc_env.agents.planning.planner import make_plan
from poc_env.cli import main
from poc_env.geometry import rectangle_polygon


@pytest.fixture(scope="module")
def plan():
    return make_plan("small", seed=3, popsize=20, maxiter=40)


def test_plan_is_feasible_and_inside_its_rectangles(plan):
    assert plan["schema"] == 2 and len(plan["uavs"]) == 3
    for u in plan["uavs"]:
        r = u["rectangle"]
        rect = rectangle_polygon(
            r["center_m"], r["length_m"], r["width_m"], np.radians(r["theta_deg"])
        )
        assert all(rect.buffer(1e-6).contains(Point(p)) for p in u["waypoints_m"])
        assert u["feasible"]
        assert u["pos"] == pytest.approx(u["poc"] * u["pod"])
    assert plan["posc"] <= plan["upper_bound"] + 1e-12
    assert plan["history"][-1] <= plan["history"][0]


def test_plan_is_reproducible(plan):
    again = make_plan("small", seed=3, popsize=20, maxiter=40)
    assert again["uavs"] == plan["uavs"] and again["history"] == plan["history"]
    other = make_plan("small", seed=4, popsize=20, maxiter=40)
    assert other["uavs"] != plan["uavs"]


def test_plan_with_many_overlapping_uavs_finishes():
    """42 UAVs from one airfield on the small map (issue 24: the exclusive masses went by
    inclusion-exclusion, 2^n terms, and this took minutes): the plan is made with a tiny
    budget, one rectangle per UAV, its POC at most the prior's mass."""
    plan = make_plan("small", uavs=42, seed=0, popsize=4, maxiter=1)
    assert len(plan["uavs"]) == 42
    assert sum(u["poc"] for u in plan["uavs"]) <= 1.0 + 1e-9


def test_cli_plan_writes_a_plan_that_exports(tmp_path, capsys):
    out = tmp_path / "plan.json"
    argv = [
        "plan",
        "--scenario",
        "small",
        "--popsize",
        "12",
        "--maxiter",
        "10",
        "--quiet",
        "--out",
        str(out),
        "--plot",
        str(tmp_path / "plan.png"),
    ]
    assert main(argv) == 0
    assert "POS_C" in capsys.readouterr().out
    plan = load_plan(out)
    assert plan["optimizer"]["name"] == "adaptive_de"
    (gj,) = export_plan(out, "geojson", "45,126")
    assert json.loads(gj.read_text())["type"] == "FeatureCollection"
    assert (tmp_path / "plan.png").read_bytes()[:4] == b"\x89PNG"
    assert (
        main(["plan", "--scenario", "small", "--optimizer", "magic", "--quiet", "--out", str(out)])
        == 2
    )


def test_cli_plan_says_wrote_only_once_both_files_are_in_place(tmp_path, monkeypatch):
    """``plan --plot`` printed ``wrote PLOT`` while the PNG was still staged (published after
    the line): every ``wrote PATH`` line must name a file that is there when it is printed."""
    import io
    import sys

    seen: list[tuple[str, bool]] = []

    class Watch(io.StringIO):
        def write(self, text):
            for line in text.splitlines():
                if line.startswith("wrote "):
                    seen.append((line[6:], Path(line[6:]).is_file()))
            return super().write(text)

    monkeypatch.setattr(sys, "stdout", Watch())
    out, png = tmp_path / "plan.json", tmp_path / "plan.png"
    argv = ["plan", "--scenario", "small", "--popsize", "12", "--maxiter", "5", "--quiet",
            "--out", str(out), "--plot", str(png)]  # fmt: skip
    assert main(argv) == 0
    assert sorted(seen) == [(str(out), True), (str(png), True)]


def test_an_allocation_plan_that_reaches_nothing_says_why(tmp_path, capsys):
    """Audit i24: an airfield 300 km from the area with 40-minute UAVs. ``plan --planner de``
    refuses (``uav.endurance_h: ... at least 2.57 h``); the allocation planner writes its
    documented empty plan with a ``reason``, but the command printed only zeros
    (``POS_C = 0.0000``). The reason is printed with the plan's table."""
    import yaml

    sc = {"name": "far", "map": {"width_km": 40, "height_km": 40, "cell_km": 5},
          "airfields": [{"name": "A", "position_km": [-300, 20]}],
          "fleet": [{"takeoff": "A", "count": 2}], "uav": {"endurance_h": 0.6667}}  # fmt: skip
    path = tmp_path / "far.yaml"
    path.write_text(yaml.safe_dump(sc))
    out = tmp_path / "p.json"
    argv = ["plan", "--scenario", str(path), "--planner", "allocation", "--quiet"]
    assert main([*argv, "--out", str(out)]) == 0
    plan = json.loads(out.read_text())
    assert plan["posc"] == 0 and plan["reason"]
    assert f"no search planned: {plan['reason']}" in capsys.readouterr().out


def test_plan_warns_when_the_sample_points_are_wider_apart_than_the_sweep(tmp_path, capsys):
    """config-audit: with ``cell_km / samples_per_cell`` above the sweep width, eq. 14 sees a
    track only on the sample rows, and an allocation plan laid on them planned more than the
    rule-aware bound (0.883 against 0.856; flown 0.852). ``plan`` now says so, naming the
    field and the samples that would do; a lattice at most W apart gets no warning."""
    out = tmp_path / "p.json"
    argv = ["plan", "--scenario", "small", "--planner", "allocation", "--refine", "0",
            "--quiet", "--out", str(out)]  # fmt: skip
    assert main([*argv, "--overrides", "map.cell_km=20"]) == 0  # 20 / 4 = 5 km > W 2.5 km
    said = capsys.readouterr().err  # warnings on stderr (i24-missionfix)
    assert "warning: sensor.samples_per_cell 4: the sensor's sample points are 5 km apart" in said
    assert "samples_per_cell >= 8" in said
    assert main(argv) == 0  # 5 / 4 = 1.25 km <= W
    assert "samples_per_cell" not in capsys.readouterr().out


def test_a_de_plan_beyond_the_endurance_says_so():
    """A DE plan whose optimiser budget found no feasible rectangle for a UAV (flight time
    beyond 0.85 T, eq. 18; the table's ``ok`` column "NO") is returned as it is, with a
    warning naming the UAV (scale-audit: a 24-UAV DE plan at popsize 16 / maxiter 20 had every
    UAV at 6-30 h on a 5 h UAV, exit status 0 and not a word, then 24 QGC missions). A
    feasible plan says nothing."""
    import warnings

    with pytest.warns(UserWarning, match=r"plan\.uavs\[1\] \(UAV 2\): flight time [\d.]+ h.*"
                      r"usable endurance [\d.]+ h.*eq\. 18.*--maxiter"):  # fmt: skip
        plan = make_plan("small", popsize=4, maxiter=1)
    assert [u["feasible"] for u in plan["uavs"]] == [True, False, True]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        plan = make_plan("small", popsize=8, maxiter=1)
    assert all(u["feasible"] for u in plan["uavs"])
