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


@pytest.fixture
def fly():
    """Fly a policy's episode and count its eq. 20 steps
    (:func:`poc_env.agents.testing.flights.fly`)."""
    from poc_env.agents.testing.flights import fly

    return fly
