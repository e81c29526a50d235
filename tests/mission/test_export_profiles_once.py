"""One export computes each UAV's terrain profile once, and the profile's simplification is
linear with the points it keeps unchanged (export-scale; found by the scale audit,
results/audit/scale/README.md, defect 4: a 24-UAV DE plan took about 2 min a format, 243 s of
a 251 s profile in ``plan_profiles``, 72 profiles for 24 UAVs, 175 s in ``_simplify``)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from poc_env.agents.mission import terrain
from poc_env.agents.mission.export import export_plan
from poc_env.agents.mission.plan import write_plan
from poc_env.agents.planning.planner import make_plan
from poc_env.config import load_scenario

_spec = importlib.util.spec_from_file_location(
    "_terrain_tests", Path(__file__).parent / "test_terrain.py"
)
assert _spec is not None and _spec.loader is not None
_t = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_t)


@pytest.mark.parametrize("fmt", ["geojson", "kml", "qgc"])
def test_each_uavs_profile_is_computed_once_an_export(tmp_path, fmt, monkeypatch):
    plan = make_plan(load_scenario(_t._scenario(_t._dem(tmp_path / "d.tif"))),
                     planner="allocation", refine=0)  # fmt: skip
    write_plan(plan, tmp_path / "plan.json")
    calls = []
    real = terrain.profile
    monkeypatch.setattr(terrain, "profile", lambda *a, **k: calls.append(1) or real(*a, **k))
    export_plan(tmp_path / "plan.json", fmt, out_dir=tmp_path / fmt)
    assert len(calls) == len(plan["uavs"]), f"{len(calls)} profiles for {len(plan['uavs'])} UAVs"


def _simplify_by_samples(dist, z, floor, vertex):
    """The simplification before export-scale (O(m^2) per leg): the reference."""
    keep = [0]
    i = 0
    n = len(z)
    while i < n - 1:
        j = i + 1
        while j + 1 < n and vertex[j] < 0:
            cand = j + 1
            seg = slice(i, cand + 1)
            frac = (dist[seg] - dist[i]) / max(dist[cand] - dist[i], 1e-9)
            line = z[i] + (z[cand] - z[i]) * frac
            if np.all(line >= floor[seg] - 1e-6):
                j = cand
            else:
                break
        keep.append(j)
        i = j
    return keep


def _random_profile(rng, m):
    """Profiles as :func:`terrain.profile` makes them, and harder ones: ramps at a pitch
    bound (points on one line, where the floor touches the legs), plateaus, noise, a floor
    at the profile or 25 m below it, or 1e-6 m above it (the sample test's slack: there
    rounding decides), a few vertices, steps of equal or random length."""
    step = rng.choice([500.0, rng.uniform(1.0, 1e3)])
    gaps = np.full(m - 1, step) if rng.random() < 0.5 else rng.uniform(0.1, 2.0, m - 1) * step
    dist = np.concatenate([[0.0], np.cumsum(gaps)])
    kind = rng.integers(4)
    if kind == 0:  # piecewise linear: ramps and plateaus (the pitch-bound passes)
        knots = np.sort(rng.choice(m, size=min(m, 6), replace=False))
        z = np.interp(np.arange(m), knots, rng.uniform(500, 3000, len(knots)))
    elif kind == 1:
        z = 1000 + np.cumsum(rng.normal(0, 20, m))
    elif kind == 2:
        z = np.round(rng.uniform(500, 600, m), 0)  # ties
    else:
        z = 2000 + 0.05 * dist  # one straight ramp
    req = z - rng.choice([0.0, rng.uniform(0, 60)], m) * (rng.random(m) < 0.7)
    floor = np.maximum(req, z - terrain.PROFILE_TOLERANCE_M)
    if rng.random() < 0.3:  # the sample test's 1e-6 m slack used up: decided by rounding
        tie = rng.random(m) < 0.5
        floor[tie] = z[tie] + 1e-6
    vertex = -np.ones(m, dtype=int)
    vertex[0], vertex[-1] = 0, m
    vertex[rng.choice(m, size=rng.integers(0, 4))] = 1
    return dist, z, floor, vertex


def test_the_linear_simplification_keeps_the_same_points(tmp_path, monkeypatch):
    rng = np.random.default_rng(20261129)
    for _ in range(400):
        args = _random_profile(rng, int(rng.integers(2, 300)))
        assert terrain._simplify(*args) == _simplify_by_samples(*args)
    # and the profiles the terrain tests' DEM gives (their first 400
    # samples: the reference is the quadratic test this replaced)
    plan = make_plan(load_scenario(_t._scenario(_t._dem(tmp_path / "d.tif"))),
                     planner="allocation", refine=0)  # fmt: skip
    seen = []
    real = terrain._simplify
    monkeypatch.setattr(terrain, "_simplify", lambda *a: seen.append(a) or real(*a))
    terrain.plan_profiles(plan)
    assert seen
    for args in seen:
        head = [np.asarray(a)[:400] for a in args]
        assert real(*head) == _simplify_by_samples(*head)
