"""The hostile-input campaign in the suite (issue 15): every external input -- scenario
overrides, maps, region files, plan.json, command lines, actions -- gives a clear project error
or a valid result; never a traceback, never a silent wrong answer.

The strategies and checks live in :mod:`poc_env.agents.testing.campaign` (one implementation);
``poc-env bench campaign --cases 5000`` runs the large campaign, the ``slow`` test a larger one.
"""

from __future__ import annotations

import pytest

from poc_env.agents.testing.campaign import TARGETS, SilentWrong, classify, run_target

#: Cases per target in the default suite (the CLI and region cases cost most).
DEFAULT_CASES = {
    "overrides": 150,
    "maps": 200,
    "regions": 40,
    "plans": 200,
    "cli": 40,
    "actions": 150,
    "geo": 60,
    "text": 60,
    "utm": 150,
    "runtime": 40,
}


def _assert_clean(name: str, cases: int, seed: int) -> None:
    counts, bad = run_target(name, cases, seed)
    assert sum(counts.values()) == cases
    shown = "\n".join(f"{d.strip()[-400:]}\n  case: {c!r:.300}" for d, c in bad[:3])
    assert not bad, f"{name}: {dict(counts)}\n{shown}"
    assert counts["error"] > 0  # the strategies do reach the validation


@pytest.mark.parametrize("name", sorted(TARGETS))
def test_campaign_target_is_clean(name):
    _assert_clean(name, DEFAULT_CASES[name], seed=0)


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(TARGETS))
def test_campaign_target_is_clean_long(name):
    _assert_clean(name, 10 * DEFAULT_CASES[name], seed=1)


def test_classify_tells_the_outcomes_apart():
    from poc_env.errors import ConfigError, PocEnvError

    def raises(exc):
        def fn(_):
            raise exc

        return fn

    assert classify(lambda _: None, 0)[0] == "ok"
    assert classify(raises(ConfigError("x", 1, "a number")), 0)[0] == "error"
    assert classify(raises(PocEnvError("no hint")), 0)[0] == "unclear"
    assert classify(raises(KeyError("k")), 0)[0] == "traceback"
    assert classify(raises(SilentWrong("nan in output")), 0)[0] == "silent"


def test_the_checks_catch_a_silent_wrong_map(monkeypatch):
    # a validator that stopped normalising must be caught as "silent", not pass as "ok"
    import numpy as np

    import poc_env.theory.probability_map as pm
    from poc_env.agents.testing.campaign import run_maps

    monkeypatch.setattr(pm, "validate_map", lambda values, grid, source="map": np.asarray(values))
    assert classify(run_maps, np.full((8, 8), 0.5))[0] == "silent"
