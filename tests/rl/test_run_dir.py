"""A run folder named after the scenario stays under runs/ (issue 27 item 2: a scenario
``name:`` of ``../../../X`` or an absolute path wrote outside it)."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("stable_baselines3", reason="the rl extra is not installed")

from poc_env.agents.rl.args import TrainArgs
from poc_env.agents.rl.train import _new_run_dir


@pytest.mark.parametrize("name", ["../../../X", "/tmp/abs", "..", "a\nb: 1", "C:\\win\\x", "é ü"])
def test_a_hostile_scenario_name_stays_one_folder_under_runs(tmp_path, monkeypatch, name):
    monkeypatch.chdir(tmp_path)
    run = _new_run_dir(TrainArgs(), name)
    assert run.parent == Path("runs") and len(run.parts) == 2
    assert (tmp_path / run).resolve().parent == (tmp_path / "runs").resolve()
    assert not run.name.startswith(".") and ".." not in run.name


def test_an_ordinary_name_is_kept(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert _new_run_dir(TrainArgs(), "paper_6_2").name.startswith("paper_6_2-sb3-")
