"""Shared fixtures of the training tests: one torch thread, and checkpoint weight equality."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import torch as th

from poc_env.agents.rl.checkpoint import load_policy


@pytest.fixture(scope="module", autouse=True)
def one_thread():
    """Every training test on one torch thread (the suite runs two workers on two cores)."""
    threads = th.get_num_threads()
    th.set_num_threads(1)
    yield
    th.set_num_threads(threads)


def _weights(model) -> list[np.ndarray]:
    if isinstance(model, (str, Path)):
        model = load_policy(Path(model))
    return [p.detach().numpy().copy() for p in model.policy.parameters()]


@pytest.fixture(scope="session")
def same_weights() -> Callable[[object, object], bool]:
    """``same_weights(a, b)``: whether two policies (model files or loaded SB3 models) have the
    same parameters, bit for bit."""

    def same(a, b) -> bool:
        x, y = _weights(a), _weights(b)
        return len(x) == len(y) and all(np.array_equal(p, q) for p, q in zip(x, y))

    return same
