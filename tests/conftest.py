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


#: How far a figure a page quotes may be from what its command prints on another CPU: the
#: planners' floating point may differ in its last bits across x86-64 CPUs, and a page rounds
#: to 4 decimals; the stale figures the docs audit found were 0.0064-0.0195 off.
FIGURE_TOL = 0.005


def _figures_in(expected: str, printed: str, tol: float = FIGURE_TOL) -> str | None:
    """None if ``printed`` holds ``expected`` (spaces normalised) with each decimal number in it
    within ``tol``; else what went wrong."""
    import re

    want = " ".join(expected.split())
    numbers = re.findall(r"\d+\.\d+", want)
    pattern = r"\d+\.\d+".join(re.escape(part) for part in re.split(r"\d+\.\d+", want))
    pattern = pattern.replace(r"\d+\.\d+", r"(\d+\.\d+)")
    found = re.search(pattern, " ".join(printed.split()))
    if found is None:
        return f"{want!r} (its numbers aside) not printed"
    for w, got in zip(numbers, found.groups()):
        if abs(float(w) - float(got)) > tol:
            return f"{want!r}: printed {got} for {w} (tolerance {tol})"
    return None


@pytest.fixture
def figures_in():
    """:func:`_figures_in`: a page's quoted figures against what its command printed."""
    return _figures_in
