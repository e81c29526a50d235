"""Recorded episodes per registered task (poc_env.recorded): a task id names a fixed MDP.

Every registered task has a recording in ``tests/recorded/`` (observations, rewards,
terminations, truncations and every numeric info of one fixed-seed, fixed-action episode
through ``gymnasium.make``), and flying it again today gives the same numbers. A change to an
observation, a reward, the dynamics or the episode end fails here until the task's version is
bumped (a new id, recorded with ``poc-env record --task <new id>``); old ids keep their
behaviour. A new task fails until it is recorded.

Tolerance (docs/CONTRIBUTING.md, "Numbers recorded elsewhere"): the recordings are replayed on
whatever x86-64 CPU runs the tests, so float64 values are compared with ``rtol=1e-7,
atol=1e-9`` and the float32 observations with ``rtol=1e-6, atol=1e-7`` (one or two float32
units in the last place of values in [-1, 2]). Measured when recorded: another process on the
recording machine gave bit-identical files; the same machine with numpy's SIMD dispatch held at
the X86_V2 baseline and numba compiling for a generic CPU
(``NPY_DISABLE_CPU_FEATURES="X86_V3 X86_V4 AVX512_ICL AVX512_SPR" NUMBA_CPU_NAME=generic``)
moved float64 infos and rewards by at most 3.9e-16 absolute (1.6e-13 relative on values near
1e-3) and no float32 observation at all. The compiled kernels have changed since (which
change moved which bits was not traced): on 2026-11-29 the replays differ from the files in
the last bits of 7,429 of 129,262 float64 values, at most 2.3e-15 absolute (2.8e-13
relative), natively and under the emulated Haswell and oldest x86-64 CPUs alike
(results/audit/cpu). A changed environment moves POS, POSC and the observations by
1e-6 and far more; booleans, integers and shapes are compared exactly.
"""

from __future__ import annotations

import numpy as np
import pytest

from poc_env import recorded, tasks
from poc_env.cli import main

ALL = list(tasks.TASKS)
#: Cross-CPU tolerances (module docstring: measured spread at most 2.3e-15 abs on float64, 0 on
#: float32).
F64 = {"rtol": 1e-7, "atol": 1e-9}
F32 = {"rtol": 1e-6, "atol": 1e-7}


def assert_same_episode(want: dict[str, np.ndarray], got: dict[str, np.ndarray], tid: str):
    assert sorted(got) == sorted(want), f"{tid}: recorded arrays differ (a new or lost info key)"
    for key, w in want.items():
        g = got[key]
        msg = f"{tid}: {key} differs from its recording; bump the task version (tasks.VERSION)"
        assert g.shape == w.shape and g.dtype == w.dtype, f"{msg}: {g.shape} {g.dtype}"
        if w.dtype == np.float64:
            np.testing.assert_allclose(g, w, err_msg=msg, **F64)
        elif w.dtype == np.float32:
            np.testing.assert_allclose(g, w, err_msg=msg, **F32)
        else:  # bool, int, the id: exact
            np.testing.assert_array_equal(g, w, err_msg=msg)


@pytest.mark.parametrize("tid", ALL)
def test_recorded_episode_replays(tid):
    path = recorded.path_of(tid)
    if not path.exists():
        pytest.fail(f"{tid} has no recording: run `poc-env record --task {tid}` and commit {path}")
    want = recorded.load(tid)
    assert str(want["task"]) == tid
    assert want["reset_seed"] == recorded.RESET_SEED
    assert_same_episode(want, recorded.replay(want), tid)


def test_every_recording_is_a_registered_task():
    """A recording without its task means an id was removed or renamed: old ids stay."""
    names = {p.stem for p in recorded.DEFAULT_DIR.glob("*.npz")}
    registered = {recorded.path_of(t).stem for t in ALL}
    assert names == registered


def test_recordings_exercise_the_episode():
    """The recordings sense (POSC grows in every one), and between them the UAVs crash, land,
    detect the target, break constraints and reach the end of an episode."""
    seen = {"crashed": False, "landed": False, "target_detected": False, "terminated": False}
    for tid in ALL:
        rec = recorded.load(tid)
        assert rec["info_posc"][-1] > rec["info_posc"][0], tid
        for key in ("crashed", "landed", "target_detected"):
            seen[key] |= bool(rec[f"info_{key}"].any())
        seen["terminated"] |= bool(rec["terminated"].any())
    assert all(seen.values()), seen


def test_the_recorder_writes_what_a_run_gives(tmp_path, capsys):
    tid = f"poc_env/UAVSearch-Small-Waypoint-v{tasks.VERSION}"  # moves with the version
    assert main(["record", "--task", tid, "--dir", str(tmp_path)]) == 0
    assert str(recorded.path_of(tid, tmp_path)) in capsys.readouterr().out
    assert [p.name for p in tmp_path.iterdir()] == [recorded.path_of(tid).name]  # no temp left
    got = recorded.load(tid, tmp_path)
    again = recorded.run(tid)  # same process, same machine: bit-identical
    assert sorted(got) == sorted(again)
    for key in got:
        np.testing.assert_array_equal(got[key], again[key], err_msg=key)
    assert_same_episode(recorded.load(tid), got, tid)  # and the committed one, cross-CPU


def test_recorded_actions_are_fixed():
    for tid in (ALL[0], ALL[1]):
        a = recorded.draw_actions(tid)
        np.testing.assert_array_equal(a, recorded.draw_actions(tid))
        assert a.dtype == np.float32 and np.abs(a).max() <= 1.0
