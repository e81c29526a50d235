"""``agents/benchmarks/compass_kernel.py``: the observation kernels timed on captured states."""

from __future__ import annotations

from poc_env._kernels import observations as kernels
from poc_env.agents.benchmarks import compass_kernel


def test_kernels_are_timed_on_captured_states_and_restored():
    before = {name: getattr(kernels, name) for name in compass_kernel.KERNELS}
    states = compass_kernel._states("make_vec_small", 0, envs=2)
    assert {name: len(v) for name, v in states.items()} == {"compass": 5, "coarse_poc": 5}
    assert states["compass"][0][0].shape[0] == 2  # each env's coarse POC, captured as passed
    assert all(getattr(kernels, name) is fn for name, fn in before.items())
    r = compass_kernel.time_kernels("make_vec_small", 3, envs=2)
    assert set(r) == set(compass_kernel.KERNELS) and all(ms > 0 for ms in r.values())
