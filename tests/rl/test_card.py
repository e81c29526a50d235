"""poc_env.agents.rl.card: a checkpoint's card from its run's config and a poc-env evaluate
folder."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
import scipy.stats

from poc_env.agents.rl.card import main, make_card
from poc_env.cli import main as cli
from poc_env.errors import ConfigError


@pytest.fixture(scope="module")
def evaluation(tmp_path_factory):
    out = tmp_path_factory.mktemp("ev") / "ev"
    argv = ["evaluate", "--scenario", "small", "--random-priors", "--policies", "lawnmower,random"]
    assert cli([*argv, "--episodes", "3", "--quiet", "--out", str(out)]) == 0
    return out


def test_card_holds_the_config_and_the_policys_episodes(evaluation, tmp_path):
    run = tmp_path / "run"
    run.mkdir()
    (run / "config.json").write_text(json.dumps({"task": "T", "seed": 4, "run_dir": "x"}))
    path = main([str(run / "step_96.zip"), "--run", str(run), "--evaluation", str(evaluation),
                 "--policy", "lawnmower", "--out", str(tmp_path / "card.json")])  # fmt: skip
    card = json.loads(path.read_text())
    rows = [r for r in csv.DictReader((evaluation / "episodes.csv").open())]
    posc = [float(r["posc"]) for r in rows if r["policy"] == "lawnmower"]
    assert card["task"] == "T" and card["seed"] == 4 and "run_dir" not in card
    assert card["model_step"] == 96
    ev = card["evaluation"]
    assert ev["seeds"] == [1000, 1001, 1002] and ev["posc"] == pytest.approx(posc)
    assert ev["floor"] == pytest.approx(min(posc))
    t = scipy.stats.t.ppf(0.975, 2)  # Student's t over 3 episodes
    assert ev["posc_ci95"] == pytest.approx(t * np.std(posc, ddof=1) / np.sqrt(3))


def test_one_episode_and_bad_input(evaluation, tmp_path):
    rows = list(csv.DictReader((evaluation / "episodes.csv").open()))
    one = tmp_path / "one"
    one.mkdir()
    (one / "evaluate.txt").write_text("x\n")
    with (one / "episodes.csv").open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerow(rows[0])
    card = make_card(tmp_path / "m.zip", None, one, rows[0]["policy"], recipe="pilot")
    assert card["recipe"] == "pilot" and card["model_step"] is None
    assert card["evaluation"]["posc_ci95"] == 0.0  # no NaN from one episode
    with pytest.raises(ConfigError, match="policy"):
        make_card(tmp_path / "m.zip", None, evaluation, "nope")
    with pytest.raises(ConfigError, match="evaluation"):
        make_card(tmp_path / "m.zip", None, tmp_path, "lawnmower")
    with pytest.raises(ConfigError, match="run"):
        make_card(tmp_path / "m.zip", tmp_path / "norun", evaluation, "lawnmower")
