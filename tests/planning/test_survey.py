"""The §6.1.1 survey (Table 4 analog) and the command line around it."""

import csv

import numpy as np
import pytest

from poc_env.agents.planning.survey import RegionPlan, RegionSpec, load_regions, run_survey
from poc_env.cli import main
from poc_env.config import load_scenario
from poc_env.errors import ConfigError, GeometryError
from poc_env.theory.probability_map import build_prior

TABLE4 = {  # No.: (search track km, POD, POC)
    1: (1143.7, 0.9784, 0.1611),
    2: (1182.5, 0.9878, 0.1600),
    3: (1220.6, 0.9988, 0.1233),
    4: (1347.7, 0.9152, 0.2146),
    5: (1210.2, 0.9987, 0.1288),
    6: (1265.8, 0.9784, 0.1805),
}


@pytest.fixture(scope="module")
def survey():
    return run_survey("paper_6_1")


def test_table4_analog(survey):
    assert [r.id for r in survey.rows] == [1, 2, 3, 4, 5, 6]
    for r in survey.rows:
        track_km, pod, _ = TABLE4[r.id]
        assert r.pod == pytest.approx(pod, abs=6e-5)  # eq. 10 with W = 22 km
        # polygons have Table 4's area, so the search legs come close to its track lengths
        assert r.search_length_km == pytest.approx(track_km, rel=0.08)
        assert r.track_length_km >= r.search_length_km
        assert r.pos == pytest.approx(r.poc * r.pod)
        assert r.feasible
    assert survey.posc == pytest.approx(sum(r.pos for r in survey.rows))
    assert survey.posc <= survey.bound <= survey.ceiling


def test_paper_6_1_prior_reproduces_table4_poc(survey):
    for r in survey.rows:
        assert r.poc == pytest.approx(TABLE4[r.id][2], abs=2e-4)
    assert survey.posc == pytest.approx(0.9404, abs=5e-4)  # Table 4's POS_C


def test_flown_pos_conserves_mass(survey):
    # everything found by flying plus what is left equals the prior's mass
    assert 0 < survey.posc_flown <= 1.0
    assert sum(r.pos_flown for r in survey.rows) == pytest.approx(survey.posc_flown)


def test_region_plan_validation():
    with pytest.raises(GeometryError):
        RegionSpec(id=1, vertices_m=((0, 0), (10, 10), (10, 0), (0, 10)))
    with pytest.raises(ConfigError, match="radius_km"):
        RegionSpec(id=1, kind="circle", center_m=(0.0, 0.0), radius_m=-1.0)
    with pytest.raises(ConfigError, match="pattern"):
        RegionSpec(id=1, vertices_m=((0, 0), (10, 0), (10, 10)), pattern="sector")
    with pytest.raises(ConfigError, match="regions"):
        load_regions("no_such_plan")
    too_many = RegionPlan(
        name="x",
        regions=tuple(
            RegionSpec(id=k, vertices_m=((0, 0), (1e4, 0), (1e4, 1e4))) for k in range(4)
        ),
    )
    with pytest.raises(ConfigError, match="at most"):
        run_survey("small", too_many)


def test_circle_patterns_are_scored():
    sc = load_scenario("small")
    plan = RegionPlan(
        name="circles",
        regions=(
            RegionSpec(id=1, kind="circle", center_m=(12e3, 25e3), radius_m=6e3, spacing_m=2e3),
            RegionSpec(
                id=2,
                kind="circle",
                center_m=(28e3, 14e3),
                radius_m=6e3,
                pattern="expanding_square",
                spacing_m=2.5e3,
            ),
            RegionSpec(id=3, kind="circle", center_m=(20e3, 20e3), radius_m=8e3, pattern="spiral"),
        ),
    )
    res = run_survey(sc, plan, prior=build_prior(sc.map))
    assert [r.pattern for r in res.rows] == ["sector", "expanding_square", "spiral"]
    assert all(0 < r.pod <= 1 and r.poc > 0 for r in res.rows)
    assert res.posc <= res.bound


def test_cli_survey_writes_files(tmp_path, capsys):
    assert main(["survey", "--scenario", "paper_6_1", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "POS_C" in out and "physical optimum" in out
    rows = list(csv.DictReader((tmp_path / "survey.csv").open()))
    assert len(rows) == 6 and float(rows[0]["bound"]) >= float(rows[0]["posc"])
    assert (tmp_path / "survey.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_cli_survey_with_user_map(tmp_path, capsys):
    sc = load_scenario("paper_6_1")
    uniform = np.full((sc.map.ny, sc.map.nx), 1.0 / (sc.map.nx * sc.map.ny))
    np.save(tmp_path / "u.npy", uniform)
    assert main(["survey", "--map", str(tmp_path / "u.npy")]) == 0
    assert "POS_C" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["survey", "--scenario", "nope"], "scenario"),
        (["survey", "--map", "missing.npy"], "does not exist"),
        (["survey", "--regions", "nope"], "regions"),
    ],
)
def test_cli_bad_input_is_a_clear_error(argv, needle, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("error:") and needle in err and "Traceback" not in err


def test_cli_survey_of_a_moving_target_says_it_surveys_a_standing_one(capsys):
    """Issue 25 audit: ``survey`` (as ``plan`` and ``replan``) on a drifting target scored the
    regions on the prior at take-off, its optimum "for the same effort" a standing target's,
    without a word; it now warns. A standing target gets no warning."""
    drift = ["--overrides", "target.model=drift", "target.current_kmh=[25,0]"]
    assert main(["survey", "--scenario", "paper_6_1", *drift]) == 0
    said = capsys.readouterr()
    assert "warning: target.model 'drift'" in said.err  # on stderr (i24-missionfix)
    assert "warning" not in said.out
    assert main(["survey", "--scenario", "paper_6_1"]) == 0
    assert "warning" not in capsys.readouterr().err
