"""Shared test helpers (fixtures, so pytest's importlib mode finds them): tests/planning and
tests/mission use the lawnmower reference."""

from __future__ import annotations

import numpy as np
import pytest


def _usual_lawnmower(center, line_length, strip, alpha, d, start):
    """The textbook lawnmower of a strip: ceil(E/d) lines at d/2, 3d/2, ... across it."""
    n = max(1, int(np.ceil(strip / d - 1e-9)))
    e_l = np.array([np.cos(alpha), np.sin(alpha)])
    e_e = np.array([-np.sin(alpha), np.cos(alpha)])
    offs = (0.5 * strip - 0.5 * d - d * np.arange(n)) if strip >= d else np.zeros(1)
    best = None
    for order in (offs, offs[::-1]):
        for up in (True, False):
            pts = []
            for k, v in enumerate(order):
                ends = [-0.5 * line_length, 0.5 * line_length]
                if (k % 2 == 0) != up:
                    ends = ends[::-1]
                pts += [center + v * e_e + u * e_l for u in ends]
            pts = np.asarray(pts)
            if best is None or np.hypot(*(pts[0] - start)) < np.hypot(*(best[0] - start)) - 1e-12:
                best = pts
    return n, best


@pytest.fixture
def usual_lawnmower():
    """The textbook ceil(E/d) lawnmower of a strip (:func:`_usual_lawnmower`)."""
    return _usual_lawnmower


def _fly(sc, policy, seed=0):
    """(no-fly steps, out-of-bounds steps, UAVs landed) of one episode of ``policy`` on the
    scenario ``sc``: the environment's eq. 20 infos ``violation_no_fly`` and
    ``violation_out_of_bounds``, summed over the UAVs and steps."""
    import poc_env

    env = poc_env.parallel_env(sc)
    obs, _ = env.reset(seed=seed)
    policy.reset(env, seed)
    nofly = oob = 0
    while env.agents:
        obs, _, _, _, info = env.step(policy.predict(obs)[0])
        nofly += sum(int(i["violation_no_fly"]) for i in info.values())
        oob += sum(int(i["violation_out_of_bounds"]) for i in info.values())
    landed = int(env.sim_state.landed[0].sum())
    env.close()
    return nofly, oob, landed


@pytest.fixture
def fly():
    """Fly a policy's episode and count its eq. 20 steps (:func:`_fly`)."""
    return _fly
