"""The plan model: every kind of plan.json loads and rewrites byte for byte; the typed fields
name every key the checks know."""

from __future__ import annotations

import json

import pytest

from poc_env.agents.mission.plan import (
    PLAN_KEYS,
    UAV_KEYS,
    Plan,
    UavPlan,
    check_plan,
    load_plan,
    write_plan,
)
from poc_env.agents.planning.planner import make_plan
from poc_env.agents.testing.campaign import sample_plan
from poc_env.errors import ConfigError

ORIGIN = (45.75, 126.65)


@pytest.fixture(scope="module", params=["de", "allocation", "schema1"])
def plan(request):
    if request.param == "schema1":
        return sample_plan()
    return make_plan(
        "small", planner=request.param, seed=2, origin_deg=ORIGIN,
        **({"popsize": 8, "maxiter": 2} if request.param == "de" else {}),
    )  # fmt: skip


def test_a_plan_rewrites_to_the_same_bytes(plan, tmp_path):
    first = write_plan(plan, tmp_path / "a.json")
    assert first.read_text(encoding="utf-8") == json.dumps(plan, indent=1)
    second = write_plan(load_plan(first), tmp_path / "b.json")
    assert second.read_bytes() == first.read_bytes()


def test_the_typed_model_names_every_checked_key():
    assert set(Plan.__required_keys__) == PLAN_KEYS
    assert set(UavPlan.__required_keys__) == UAV_KEYS
    # layer_m: set by an export only (features.with_layers), never by a planner
    assert {"flown_rectangle", "areas_m", "layer_m", "approach_m"} == set(UavPlan.__optional_keys__)
    assert {"crs", "flight", "bounds", "airfields"} <= set(Plan.__optional_keys__)


def test_check_plan_refuses_what_is_not_a_plan():
    with pytest.raises(ConfigError, match="plan"):
        check_plan([1, 2])
    bad = sample_plan()
    del bad["uavs"][0]["pod"]
    with pytest.raises(ConfigError, match=r"plan\.uavs\[0\]\.pod"):
        check_plan(bad)


def test_an_optimizer_that_is_not_a_mapping_is_refused():
    """Found by the campaign once it exported html: the map report read optimizer.name."""
    bad = sample_plan()
    bad["optimizer"] = "adaptive_de"
    with pytest.raises(ConfigError, match=r"plan\.optimizer"):
        check_plan(bad)
