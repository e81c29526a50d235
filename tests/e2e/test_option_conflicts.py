"""Issue 27's runtime classes on the command line: options accepted and ignored are refused,
oversized work is refused up front, and plan.json names the prior file it used."""

from __future__ import annotations

import json

import numpy as np
import pytest

from poc_env.agents.rl.args import parse_train_args
from poc_env.cli import main
from poc_env.errors import ConfigError

TASK = "poc_env/UAVSearch-Small-Heading-v1"


def _err(capsys, argv) -> str:
    capsys.readouterr()
    assert main(argv) == 2
    return capsys.readouterr().err


@pytest.mark.parametrize(
    ("argv", "field"),
    [
        (["--task", TASK, "--scenario", "paper_6_1"], "scenario"),
        (["--task", TASK, "--scenario", "paper_6_2"], "scenario"),  # even the default, given
        (["--task", TASK, "--no-random-priors"], "random_priors"),
        (["--net-arch", "64"], "net_arch"),  # the shared recipe's network is a CNN
        (["--recipe", "central", "--approach-shaping", "0.1"], "approach_shaping"),
        (["--engine", "rllib", "--n-envs", "8"], "n_envs"),
        (["--rllib-policies", "per_uav"], "rllib_policies"),
        (["--bc-epochs", "3"], "bc_epochs"),
        (["--engine", "rllib", "--task", TASK, "--recipe", "pilot"], "recipe"),
    ],
)
def test_train_refuses_options_its_run_would_ignore(argv, field):
    with pytest.raises(ConfigError) as err:
        parse_train_args(argv)
    assert err.value.field == field


def test_evaluate_refuses_task_and_scenario(capsys):
    err = _err(capsys, ["evaluate", "--task", TASK, "--scenario", "paper_6_1", "--episodes", "1"])
    assert "either --task or --scenario" in err


def _file_prior_scenario(tmp_path):
    from poc_env.config import load_scenario, save_scenario

    np.save(tmp_path / "prior.npy", np.ones((8, 8)))
    over = {"map.prior.kind": "file", "map.prior.file": str(tmp_path / "prior.npy")}
    save_scenario(load_scenario("small", over), tmp_path / "s.yaml")
    return tmp_path / "s.yaml", tmp_path / "prior.npy"


def test_map_over_a_file_prior_is_refused_and_plan_json_names_the_file(tmp_path, capsys):
    yaml, prior = _file_prior_scenario(tmp_path)
    other = tmp_path / "other.npy"
    np.save(other, np.ones((8, 8)))
    for cmd in (["plan", "--maxiter", "1", "--popsize", "4", "--out", str(tmp_path / "p.json")],
                ["evaluate", "--episodes", "1", "--policies", "random"],
                ["survey"]):  # fmt: skip
        err = _err(capsys, [*cmd, "--scenario", str(yaml), "--map", str(other)])
        assert "error: map:" in err and "prior.npy" in err, cmd
    out = tmp_path / "plan.json"
    argv = ["plan", "--scenario", str(yaml), "--maxiter", "1", "--popsize", "4", "--quiet"]
    assert main([*argv, "--out", str(out)]) == 0
    assert json.loads(out.read_text())["map_source"] == str(prior)  # was "builtin"


def test_plan_refuses_options_that_do_not_apply(capsys):
    fleet = "fleet=[{takeoff: A, count: 3}]"
    err = _err(capsys, ["plan", "--scenario", "small", "--uavs", "2", "--overrides", fleet])
    assert "error: uavs:" in err
    for opt, value in (("--optimizer", "cmaes"), ("--popsize", "8"), ("--preset", "tuned")):
        err = _err(capsys, ["plan", "--scenario", "small", "--planner", "allocation", opt, value])
        assert f"error: {opt[2:]}:" in err and "--planner de" in err


def test_render_and_campaign_sizes_are_bounded_up_front(tmp_path, capsys):
    big = ["--overrides", "episode.horizon_steps=10000000", "--out", str(tmp_path / "e.gif")]
    err = _err(capsys, ["render", "--scenario", "small", *big, "--max-steps", "10000000"])
    assert "error: max_steps: got 10000000" in err and "memory limit" in err
    assert not (tmp_path / "e.gif").exists()
    from poc_env.agents.testing.campaign import main as campaign

    with pytest.raises(SystemExit) as done:
        campaign(["--cases", "1000000000"])
    assert done.value.code == 2
    assert "--cases: got 1000000000; allowed: an integer in [1, 1000000]" in capsys.readouterr().err


def test_every_overrides_example_in_the_help_parses():
    """Issue 27: ``plan --help`` showed ``uav.count=3``, a key the scenario refuses. The
    --overrides example of every subcommand's help loads on the built-in scenario."""
    import re

    from poc_env.cli import build_parser
    from poc_env.config import load_scenario, parse_overrides

    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    seen = 0
    for p in sub.choices.values():  # type: ignore[union-attr]
        text = " ".join(p.format_help().split())
        for m in re.finditer(r"\(e\.g\. ((?:[\w.]+=\S+ ?)+)\)", text):
            load_scenario("small", parse_overrides(m.group(1).split()))
            seen += 1
    assert seen >= 3
