"""One spec per contract table (poc_env.spec): the code, the docs page and these tests read it."""

from __future__ import annotations

import itertools

import gymnasium
import numpy as np
import pytest

import poc_env
from poc_env import recorded, spec, tasks
from poc_env.cli import build_parser, main
from poc_env.sim import observations as obs_mod
from poc_env.sim import rewards


def test_the_docs_page_is_the_generated_text():
    text = spec.DOC.read_text(encoding="utf-8")
    assert spec.render_doc(text) == text, "docs/environment.md is stale: poc-env spec --write"
    assert main(["spec"]) == 0


def test_spec_write_fills_the_markers(tmp_path, capsys):
    page = tmp_path / "ENV.md"
    page.write_text(
        "".join(f"<!-- spec:{n} -->\nSTALE TEXT\n<!-- /spec:{n} -->\n" for n in spec.SECTIONS),
        encoding="utf-8",
    )
    assert main(["spec", "--doc", str(page)]) == 1  # stale
    assert main(["spec", "--write", "--doc", str(page)]) == 0
    text = page.read_text(encoding="utf-8")
    assert "STALE TEXT" not in text and spec.markdown("infos") in text
    assert main(["spec", "--doc", str(page)]) == 0
    page.write_text("no markers", encoding="utf-8")
    capsys.readouterr()
    assert main(["spec", "--doc", str(page)]) == 2  # cli-audit: was a KeyError traceback
    assert "error: doc: " in capsys.readouterr().err


@pytest.mark.parametrize("obs_type", ["dict", "flat", "compass"])
def test_observation_spaces_are_the_spec(obs_type):
    env = poc_env.parallel_env("small", obs_type=obs_type)
    space = env.observation_space("uav_0")
    g = env.params.grid
    vlow, vhigh = spec.bounds(spec.VECTOR)
    if obs_type == "compass":
        low, high = spec.compass_bounds()
        np.testing.assert_array_equal(space.low, low)
        np.testing.assert_array_equal(space.high, high)
        assert space.shape == (spec.COMPASS_SIZE,)
    else:
        box = space["vector"] if obs_type == "dict" else space
        low = box.low if obs_type == "dict" else box.low[-len(spec.VECTOR) :]
        high = box.high if obs_type == "dict" else box.high[-len(spec.VECTOR) :]
        np.testing.assert_array_equal(low, vlow)
        np.testing.assert_array_equal(high, vhigh)
        raster = (len(spec.RASTER), g.ny, g.nx)
        if obs_type == "dict":
            assert space["raster"].shape == raster
        else:
            assert space.shape == (int(np.prod(raster)) + len(spec.VECTOR),)
    obs, _ = env.reset(seed=0)
    assert all(space.contains(o) for o in obs.values())


def test_the_observation_module_reads_the_spec():
    assert spec.names(spec.RASTER) == obs_mod.RASTER_NAMES
    assert spec.names(spec.VECTOR) == obs_mod.VECTOR_NAMES
    assert obs_mod.FEATURES == spec.COMPASS_SIZE == sum(b.size for b in spec.COMPASS)
    blocks = spec.compass_offsets()
    assert blocks["vector"] == slice(0, len(spec.VECTOR))
    assert blocks["index"].stop == spec.COMPASS_SIZE


def test_compass_blocks_carry_what_the_spec_says():
    env = poc_env.parallel_env("small", obs_type="compass")
    obs, _ = env.reset(seed=1)
    b = spec.compass_offsets()
    vec = poc_env.parallel_env("small", obs_type="dict").reset(seed=1)[0]
    for k, (agent, o) in enumerate(obs.items()):
        np.testing.assert_array_equal(o[b["vector"]], vec[agent]["vector"])
        assert o[b["compass"]].sum() == pytest.approx(1.0, abs=1e-5)  # shares of the POC
        assert o[b["index"]].argmax() == k % spec.N_IDS and o[b["index"]].sum() == 1


def test_recorded_observations_lie_in_the_spec_bounds():
    for tid, task in tasks.TASKS.items():
        low, high = spec.set_bounds() if task.obs == "set" else spec.compass_bounds()
        obs = recorded.load(tid)["observation"]
        per_uav = obs.reshape(obs.shape[0], -1, low.size)
        assert (per_uav >= low).all() and (per_uav <= high).all(), tid


def test_infos_are_the_spec_keys():
    env = poc_env.parallel_env("small")
    _, infos = env.reset(seed=0)
    assert tuple(infos["uav_0"]) == spec.info_keys()
    *_, infos = env.step({a: [0.0, 0.0, 0.0] for a in env.agents})
    assert tuple(infos["uav_0"]) == spec.info_keys()
    kinds = {"float": float, "bool": bool, "int": int}
    for e in spec.INFOS:
        if "<" in e.name:
            continue
        value = infos["uav_0"][e.name]
        if e.shape == "()":
            assert type(value) is kinds[e.dtype], e.name
        else:
            assert value.shape == (env.params.n_agents,) and value.dtype == np.dtype(e.dtype)
    gym = gymnasium.make(tasks.task_id("Small", "Heading", False))
    _, info = gym.reset(seed=0)
    assert set(info) == set(spec.info_keys())


def test_a_term_or_key_missing_from_the_spec_raises(monkeypatch):
    env = poc_env.parallel_env("small")
    monkeypatch.setattr(rewards, "_TERMS", spec.names(spec.REWARD_TERMS)[:-1])
    env.reset(seed=0)
    with pytest.raises(RuntimeError, match="reward terms"):
        env.step({a: [0.0, 0.0, 0.0] for a in env.agents})
    monkeypatch.undo()
    from poc_env.envs import parallel

    monkeypatch.setattr(parallel, "INFO_KEYS", (*spec.info_keys(), "new_key"))
    with pytest.raises(RuntimeError, match="infos"):
        env.reset(seed=0)


def test_reward_terms_are_the_spec():
    from poc_env.envs.parallel import REWARD_TERMS

    assert spec.names(spec.REWARD_TERMS) == REWARD_TERMS
    assert rewards._TERMS == REWARD_TERMS


def test_the_task_table_is_the_spec():
    assert tasks.VERSION == spec.TASK_VERSION
    parts = itertools.product(spec.SCENARIO_PARTS, spec.RANDOM_PARTS, spec.CONTROL_PARTS)
    want = {
        tasks.task_id(s.text, c.text, bool(r.value), v.version): (
            s.value, c.value, r.value, v.version, v.env_control
        )
        for s, r, c in parts
        for v in spec.versions_of(c.text)
    }  # fmt: skip
    got = {
        t: (k.scenario, k.control, k.random_prior, k.version, k.kwargs["control"])
        for t, k in tasks.TASKS.items()
    }
    for m in spec.MOTION_PARTS[1:]:  # moving targets: fixed prior, the listed control levels
        for s in spec.SCENARIO_PARTS:
            for c in spec.MOTION_CONTROLS[str(m.value)]:
                for v in spec.versions_of(c):
                    tid = tasks.task_id(s.text, c, False, v.version, motion=m.text)
                    want[tid] = (s.value, tasks.CONTROL_NAMES[c], False, v.version, v.env_control)
    for o in spec.OBS_PARTS[1:]:  # the set observation: the listed controls from their version
        for v in spec.obs_versions(str(o.value)):
            ctl = tasks.CONTROL_NAMES[v.control]
            for s, r in itertools.product(spec.SCENARIO_PARTS, spec.RANDOM_PARTS):
                tid = tasks.task_id(s.text, v.control, bool(r.value), v.version, obs=o.text)
                want[tid] = (s.value, ctl, r.value, v.version, v.env_control)
            for n in spec.SIZE_PARTS:
                tid = tasks.task_id(
                    spec.SIZE_SCENARIO.text, v.control, True, v.version, obs=o.text, size=n.text
                )
                want[tid] = (spec.SIZE_SCENARIO.value, ctl, True, v.version, v.env_control)
                assert tasks.TASKS[tid].n_uavs == int(n.value)
    # Increments v0 (issue 28: BC at the teacher's level for any fleet size), Heading v1
    assert spec.obs_versions("set") == (spec.TASK_VERSIONS[0], spec.TASK_VERSIONS[2])
    assert {t.motion for t in tasks.TASKS.values()} == {str(m.value) for m in spec.MOTION_PARTS}
    assert {t.obs for t in tasks.TASKS.values()} == {str(o.value) for o in spec.OBS_PARTS}
    assert got == want
    # every id of the first release stays registered (old ids keep their behaviour)
    for s, r, c in itertools.product(spec.SCENARIO_PARTS, spec.RANDOM_PARTS, spec.CONTROL_PARTS):
        assert tasks.task_id(s.text, c.text, bool(r.value), spec.TASK_VERSION) in tasks.TASKS
    assert all(t.endswith(f"-v{tasks.TASKS[t].version}") for t in tasks.TASKS)


def test_every_version_has_its_row_in_the_history():
    text = spec.markdown("tasks")
    for v in spec.TASK_VERSIONS:
        assert f"| `{v.control}` | `v{v.version}` | `{v.env_control}` |" in text


def test_the_task_table_text_reads_the_scenarios():
    text = spec.markdown("tasks")
    assert "`small`: 3 UAVs, 40 x 40 km (8 x 8 cells of 5 km)" in text
    assert "`paper_6_2`: 6 UAVs, 200 x 150 km (40 x 30 cells of 5 km)" in text


def test_export_help_names_the_plan_schema():
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    text = sub.choices["export"].format_help()  # type: ignore[attr-defined]
    assert "schema 2" in text and "(schema 1)" not in text
