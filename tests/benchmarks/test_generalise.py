"""``poc-env bench generalise``: held-out conditions change what they say, the table's ``kept``
is the ratio of normalised scores, and bad names fail before any episode with no output."""

from __future__ import annotations

import csv
import inspect
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from poc_env.agents.benchmarks import generalise
from poc_env.agents.experiments.evaluate import episode_prior, evaluate
from poc_env.envs.parallel import UAVSearchParallelEnv
from poc_env.errors import ConfigError

KM = 1000.0


def test_each_condition_builds_the_geometry_and_comms_it_names():
    built = {c: generalise.condition_scenario("paper_6_2", c) for c in generalise.CONDITIONS}
    # (rows, cols) of the grid the env flies, cell size, belief sharing
    expected = {
        "train": ((30, 40), 5 * KM, "global"),
        "tall_150x200": ((40, 30), 5 * KM, "global"),
        "cells_6km": ((25, 33), 6 * KM, "global"),
        "comms_belief": ((30, 40), 5 * KM, "comms"),
        "comms_60km": ((30, 40), 5 * KM, "comms"),
    }
    assert set(built) == set(expected)
    for c, sc in built.items():
        shape, cell, sharing = expected[c]
        env = UAVSearchParallelEnv(scenario=sc)
        assert env.params.grid.shape == shape, c
        assert sc.map.cell_m == cell and sc.comms.belief_sharing == sharing, c
        # the airfields and the swarm stay those of the task
        assert [a.position_m for a in sc.airfields] == [(20 * KM, -60 * KM), (120 * KM, -60 * KM)]
        assert sc.n_uavs == 6
        # random priors work on the condition's own grid, from the held-out stream
        prior = episode_prior(sc, 1000)
        assert prior.shape == shape and prior.sum() == pytest.approx(1.0)
        obs, _ = env.reset(seed=1000, options={"prior": prior})
        assert len(obs) == 6
    assert built["cells_6km"].map.width_m == 198 * KM  # 33 whole cells of 6 km
    assert built["comms_60km"].comms.range_m == 60 * KM
    assert built["comms_belief"].comms.range_m == built["train"].comms.range_m
    # train is always flown first: it is the reference of kept
    assert generalise.conditions(["cells_6km", "train"]) == ["train", "cells_6km"]
    assert generalise.conditions(["tall_150x200"]) == ["train", "tall_150x200"]
    # the default first seed is evaluate's
    assert inspect.signature(evaluate).parameters["seed0"].default == generalise.SEED0


def test_tiny_run_writes_one_row_per_condition_and_policy(tmp_path, capsys):
    out = tmp_path / "out"
    argv = ["--episodes", "2", "--policies", "lawnmower,random", "--quiet"]
    argv += ["--conditions", "train,tall_150x200", "--out", str(out)]
    generalise.main(argv)
    saved = list(csv.DictReader((out / "generalise.csv").open()))
    pairs = [(r["condition"], r["policy"]) for r in saved]
    assert pairs == [
        ("train", "lawnmower"),
        ("train", "random"),
        ("tall_150x200", "lawnmower"),
        ("tall_150x200", "random"),
    ]
    by = {(r["condition"], r["policy"]): r for r in saved}
    for p in ("lawnmower", "random"):
        train = float(by["train", p]["normalised"])
        tall = float(by["tall_150x200", p]["normalised"])
        assert float(by["tall_150x200", p]["kept"]) == pytest.approx(tall / train, rel=1e-9)
        assert float(by["train", p]["kept"]) == pytest.approx(1.0)
    # the tall rows are the tall geometry's own evaluation (not train's numbers again)
    ev = evaluate(
        generalise.condition_scenario("paper_6_2", "tall_150x200"),
        ["lawnmower"],
        episodes=2,
        seed0=generalise.SEED0,
        random_priors=True,
    ).rows()[0]
    row = by["tall_150x200", "lawnmower"]
    assert float(row["normalised"]) == pytest.approx(ev["normalised"])
    assert float(row["bound_reach"]) == pytest.approx(ev["bound_reach"])
    assert not np.isclose(float(row["bound_reach"]), float(by["train", "lawnmower"]["bound_reach"]))
    md = (out / "generalise.md").read_text()
    lines = md.splitlines()
    assert sum(x.startswith("| tall_150x200 | ") for x in lines) == 2
    assert sum(x.startswith("| train | ") for x in lines) == 2
    assert md in capsys.readouterr().out  # the same table on stdout


@pytest.mark.parametrize(
    ("field", "argv", "named"),
    [
        ("conditions", ["--conditions", "train,wide_300km"], list(generalise.CONDITIONS)),
        ("policies", ["--policies", "lawnmower,no_such_policy"], ["lawnmower", "de_plan"]),
        ("policies", ["--policies", " , "], []),
    ],
)
def test_bad_names_fail_before_any_episode_and_write_nothing(
    tmp_path, monkeypatch, field, argv, named
):
    import poc_env.agents.experiments.evaluate as ev_mod

    calls = []
    monkeypatch.setattr(ev_mod, "evaluate", lambda *a, **k: calls.append(a))
    out = tmp_path / "out"
    with pytest.raises(ConfigError) as err:
        generalise.main([*argv, "--episodes", "2", "--out", str(out)])
    assert err.value.field == field
    assert all(n in err.value.allowed for n in named)
    assert calls == [] and not out.exists() and list(tmp_path.iterdir()) == []


def test_module_reports_a_bad_condition_without_a_traceback(tmp_path):
    res = subprocess.run(
        [sys.executable, "-m", "poc_env.agents.benchmarks.generalise", "--conditions", "nope"],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=Path(__file__).resolve().parents[2],
    )
    assert res.returncode == 2
    assert res.stderr.startswith("error: conditions:") and "Traceback" not in res.stderr
    assert "tall_150x200" in res.stderr
