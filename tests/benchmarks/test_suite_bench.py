"""The baseline table (poc-env bench baselines), the suite speed benchmark and poc-env tasks."""

from __future__ import annotations

import csv

import pytest

from poc_env import tasks
from poc_env.agents.benchmarks import baselines, suite
from poc_env.cli import main as cli
from poc_env.errors import ConfigError


def test_baselines_table_scores_each_task_with_its_floor(tmp_path, capsys):
    ids = ["UAVSearch-Small-Random-Heading-v0", "UAVSearch-Small-Random-Waypoint-v0"]
    rows = baselines.main(
        ["--tasks", *ids, "--episodes", "2", "--policies", "lawnmower", "--out", str(tmp_path)]
    )
    assert [(r["task"].split("/")[1], r["policy"]) for r in rows] == [
        (ids[0], "lawnmower"),
        (ids[1], "lawnmower"),
    ]
    # the classical planners fly the same on both control levels: scored once, same numbers
    assert rows[0]["posc_mean"] == rows[1]["posc_mean"]
    assert 0 < rows[0]["normalised"] < 1 and rows[0]["bound_reach"] > rows[0]["posc_mean"]
    saved = list(csv.DictReader((tmp_path / "baselines.csv").open()))
    assert len(saved) == 2 and float(saved[0]["posc_mean"]) == rows[0]["posc_mean"]
    md = (tmp_path / "baselines.md").read_text()
    assert md.count("| UAVSearch-Small-Random-") == 2 and "poc-env bench baselines --tasks" in md


def test_baselines_default_floor_follows_the_control_level():
    args = baselines._parse(["--tasks", "UAVSearch-Small-Waypoint-v0", "--episodes", "2"])
    rows = baselines.run(args)
    assert [r["policy"] for r in rows] == ["random_waypoint", *baselines.CLASSICAL]
    assert rows[0]["posc_ci95"] > 0  # random draws differ between seeds


@pytest.mark.parametrize("bad", ["nope", "=ppo:x", "X@Joystick=ppo:x"])
def test_baselines_bad_learned(bad):
    with pytest.raises(ConfigError, match="learned"):
        baselines.run(baselines._parse(["--quick", "--learned", bad]))


def test_baselines_learned_columns_follow_the_control_level():
    argv = ["--tasks", "UAVSearch-Small-Heading-v0", "UAVSearch-Small-Waypoint-v0"]
    argv += ["--episodes", "1", "--policies", "lawnmower"]
    # a column per label; {Control} names the task's level; @Heading keeps it to Heading tasks
    argv += ["--learned", "floor={Control}", "--learned", "only@Heading=random_heading"]
    with pytest.raises(ConfigError, match="got 'Heading'"):
        baselines.run(baselines._parse(argv))
    argv[-3] = "floor=random_{control}"  # a literal: the placeholder is {Control}
    with pytest.raises(ConfigError, match=r"random_\{control\}"):
        baselines.run(baselines._parse(argv))
    argv[-3] = "floor=random_waypoint"
    rows = baselines.run(baselines._parse(argv))
    got = [(r["task"].split("-")[2], r["label"], r["policy"]) for r in rows]
    assert got == [
        ("Heading", "lawnmower", "lawnmower"),
        ("Heading", "floor", "random_waypoint"),
        ("Heading", "only", "random_heading"),
        ("Waypoint", "lawnmower", "lawnmower"),
        ("Waypoint", "floor", "random_waypoint"),
    ]
    md = baselines.to_markdown(rows, "cmd")
    assert "| task | lawnmower | floor | only |" in md


def test_baselines_policies_are_a_comma_list_as_evaluate_reads_it():
    """Audit (i28-audit): ``--policies "random_waypoint, lawnmower"`` was refused (``got '
    lawnmower'``) where ``evaluate --policies`` strips each name."""
    argv = ["--tasks", "UAVSearch-Small-Waypoint-v0", "--episodes", "1"]
    rows = baselines.run(baselines._parse([*argv, "--policies", "random_waypoint, lawnmower,"]))
    assert [r["policy"] for r in rows] == ["random_waypoint", "lawnmower"]


def test_suite_env_figures_are_positive():
    tid = tasks.task_id("Small", "Heading", False)
    assert suite.bench_vector(tid, 4, runs=1) > 0
    assert suite.bench_parallel(tid, runs=1) > 0


def test_tasks_command_lists_every_task(capsys):
    assert cli(["tasks"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 1 + len(tasks.TASKS)
    assert any("UAVSearch-Paper62-Random-Heading-v0" in line and "heading" in line for line in out)


def test_quick_baselines_refuse_an_episode_count_they_would_replace():
    """``--quick`` flies 2 episodes; an ``--episodes`` beside it was silently replaced (cli-audit):
    refused, naming the option, before any episode flies."""
    with pytest.raises(ConfigError, match="--quick") as err:
        baselines.run(baselines._parse(["--quick", "--episodes", "5"]))
    assert err.value.field == "episodes"
