"""The evaluation harness: same seeds, same results, whatever the number of workers."""

import csv

import pytest

from agents.experiments.evaluate import effort_bound, evaluate
from poc_env.cli import main
from poc_env.errors import ConfigError


def test_identical_seeds_give_identical_results_and_workers_do_not_matter():
    a = evaluate("small", ["lawnmower", "random"], episodes=2)
    b = evaluate("small", ["lawnmower", "random"], episodes=2, workers=2)
    assert a.episodes == b.episodes
    rows = {r["policy"]: r for r in a.rows()}
    assert rows["lawnmower"]["posc_mean"] > rows["random"]["posc_mean"]
    assert all(e.posc <= a.bound + 1e-12 for e in a.episodes)


def test_bound_grows_with_the_fleet():
    from poc_env.config import load_scenario

    sc = load_scenario("small")
    assert effort_bound(sc.with_uavs(1)) < effort_bound(sc) <= 1.0


def test_bad_input():
    with pytest.raises(ConfigError, match="policies"):
        evaluate("small", ["telepathy"], episodes=1)
    with pytest.raises(ConfigError, match="episodes"):
        evaluate("small", ["random"], episodes=0)


def test_cli_evaluate(tmp_path, capsys):
    argv = [
        "evaluate",
        "--scenario",
        "small",
        "--policies",
        "lawnmower,random",
        "--episodes",
        "2",
        "--quiet",
        "--out",
        str(tmp_path),
    ]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "lawnmower" in out and "physical optimum" in out
    rows = list(csv.DictReader((tmp_path / "evaluate.csv").open()))
    assert [r["policy"] for r in rows] == ["lawnmower", "random"]
    assert (tmp_path / "posc_over_time.png").read_bytes()[:4] == b"\x89PNG"
    assert main(["evaluate", "--scenario", "small", "--policies", "nope", "--quiet"]) == 2


def test_policies_come_from_the_registry():
    """evaluate makes its policies by name from agents.policies.registry: an unknown name is
    refused before any episode runs, with every registered name in the message."""
    from agents.policies.registry import registered

    with pytest.raises(ConfigError) as err:
        evaluate("small", ["lawnmower", "telepathy"], episodes=1)
    assert err.value.field == "policies" and err.value.value == "telepathy"
    assert err.value.allowed == "one of " + ", ".join(registered())
    with pytest.raises(ConfigError, match="checkpoint path"):
        evaluate("small", ["ppo:"], episodes=1)
