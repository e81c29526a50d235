"""Adaptive DE (eq. 27-32) and the comparison optimisers: correct, seeded, budget-bound."""

from __future__ import annotations

import numpy as np
import pytest

from poc_env.agents.planning.objective import PlanObjective
from poc_env.agents.planning.optimizers import (
    OPTIMIZERS,
    adaptive_de,
    adaptive_mutation,
    classic_de,
    cmaes,
    get_optimizer,
    run_optimizer,
)
from poc_env.config import PlannerConfig
from poc_env.errors import ConfigError

SHIFT = np.linspace(-2.0, 3.0, 12)
BOUNDS_12 = [(-5.0, 5.0)] * 12


def shifted_sphere(x):
    return np.sum((np.atleast_2d(x) - SHIFT) ** 2, axis=-1)


@pytest.fixture(scope="module")
def small():
    return PlanObjective("small")


# --------------------------------------------------------------------------- eq. 32


def test_eq_32_starts_at_twice_f0_and_decreases_to_f0():
    gm, f0 = 300, 0.2
    f = adaptive_mutation(np.arange(gm + 1), gm, f0)
    assert f[0] == 2 * f0
    assert f[-1] == f0
    # monotone; strictly while distinguishable from F0 in floating point (lambda = e^(1-Gm/(Gm-G)))
    assert np.all(np.diff(f) <= 0)
    assert np.all(np.diff(f[f > f0 * (1 + 1e-12)]) < 0)
    assert f[gm // 2] == pytest.approx(2.0 ** np.exp(-1.0) * f0)
    # eq. 32 as printed, with the paper's 1-based counter G_paper = G + 1
    g = np.arange(gm)
    printed = 2.0 ** np.exp(1.0 - gm / (gm + 1.0 - (g + 1))) * f0
    np.testing.assert_allclose(f[:-1], printed, rtol=1e-12)


def test_runs_use_eq_32_classic_uses_constant_f():
    res = adaptive_de(shifted_sphere, BOUNDS_12, popsize=10, maxiter=20, f0=0.25, rng=0)
    assert res.mutation[0] == 0.5 and np.all(np.diff(res.mutation) < 0)
    assert res.mutation[-1] == pytest.approx(0.25, rel=1e-6)
    np.testing.assert_allclose(res.mutation, adaptive_mutation(np.arange(20), 20, 0.25))
    res = classic_de(shifted_sphere, BOUNDS_12, popsize=10, maxiter=20, f0=0.25, rng=0)
    assert np.all(res.mutation == 0.25)


# --------------------------------------------------------------------------- behaviour


@pytest.mark.parametrize("name", list(OPTIMIZERS))
def test_seeded_runs_are_reproducible(name):
    fn = OPTIMIZERS[name]
    a = fn(shifted_sphere, BOUNDS_12, popsize=12, maxiter=15, rng=7)
    b = fn(shifted_sphere, BOUNDS_12, popsize=12, maxiter=15, rng=np.random.default_rng(7))
    c = fn(shifted_sphere, BOUNDS_12, popsize=12, maxiter=15, rng=8)
    np.testing.assert_array_equal(a.history, b.history)
    np.testing.assert_array_equal(a.x, b.x)
    assert not np.array_equal(a.x, c.x)


@pytest.mark.parametrize("name", list(OPTIMIZERS))
def test_each_optimizer_improves_a_shifted_sphere(name):
    kw = {"f0": 0.5, "cr": 0.9} if name in ("adaptive_de", "classic_de") else {}
    res = OPTIMIZERS[name](shifted_sphere, BOUNDS_12, popsize=30, maxiter=60, rng=1, **kw)
    h = res.history
    assert len(h) == res.nit + 1 == 61
    assert np.all(np.diff(h) <= 0)
    assert h[-1] < 0.1 * h[0]
    assert res.fun == pytest.approx(float(shifted_sphere(res.x)[0]))
    # budget parity: about popsize x (maxiter + 1) evaluations
    assert 0.95 * 30 * 61 <= res.nfev <= 30 * 61 + 60


@pytest.mark.parametrize("name", list(OPTIMIZERS))
def test_each_optimizer_improves_the_plan_objective(name, small):
    res = OPTIMIZERS[name](small, small.bounds, popsize=16, maxiter=12, rng=3)
    assert res.fun < res.history[0]
    assert np.all(np.diff(res.history) <= 0)
    assert small(res.x) == pytest.approx(res.fun, rel=1e-12)
    lo, hi = small.bounds.T
    assert np.all((res.x >= lo) & (res.x <= hi))


def test_de_keeps_the_population_in_bounds_eq_31():
    seen = []
    res = adaptive_de(
        shifted_sphere,
        BOUNDS_12,
        popsize=20,
        maxiter=30,
        f0=1.5,  # F up to 3: many mutants leave the box
        cr=0.9,
        rng=2,
        callback=lambda r: seen.append(r.population),
    )
    assert len(seen) == res.nit == 30
    for pop in seen:
        assert np.all((pop >= -5.0) & (pop <= 5.0))
    assert res.nfev == 20 * 31


def test_vectorized_and_scalar_calls_agree():
    a = adaptive_de(shifted_sphere, BOUNDS_12, popsize=10, maxiter=10, rng=4)
    b = adaptive_de(
        lambda x: float(shifted_sphere(x)[0]),
        BOUNDS_12,
        popsize=10,
        maxiter=10,
        rng=4,
        vectorized=False,
    )
    np.testing.assert_array_equal(a.history, b.history)


def test_callback_can_stop_a_run():
    res = adaptive_de(
        shifted_sphere, BOUNDS_12, popsize=10, maxiter=50, rng=0, callback=lambda r: r.nit >= 3
    )
    assert res.nit == 3 and "callback" in res.message
    assert len(res.history) == 4


def test_staged_de_evolves_positions_then_sizes_then_angle_and_spacing():
    pops = []
    res = adaptive_de(
        shifted_sphere,
        BOUNDS_12,  # two "UAVs" of the 6n encoding
        popsize=10,
        maxiter=9,
        rng=5,
        staged=True,
        callback=lambda r: pops.append(r.population),
    )
    start = adaptive_de(shifted_sphere, BOUNDS_12, popsize=10, maxiter=0, rng=5).population
    cols = np.arange(12) % 6
    stage_cols = [(0, 1), (2, 3), (4, 5)]
    previous = start
    for g, pop in enumerate(pops):
        moving = stage_cols[g // 3]
        frozen = ~np.isin(cols, moving)
        np.testing.assert_array_equal(pop[:, frozen], previous[:, frozen])
        previous = pop
    # eq. 32 restarts in each stage
    assert res.mutation[0] == res.mutation[3] == res.mutation[6] == 0.4
    with pytest.raises(ConfigError, match="staged"):
        adaptive_de(shifted_sphere, [(-1, 1)] * 4, staged=True, maxiter=3, popsize=5)


def test_cmaes_leaves_global_random_state_alone():
    state = np.random.get_state()[1].copy()  # noqa: NPY002
    cmaes(shifted_sphere, BOUNDS_12, popsize=8, maxiter=5, rng=0)
    np.testing.assert_array_equal(np.random.get_state()[1], state)  # noqa: NPY002


def test_run_optimizer_maps_the_planner_section(small):
    planner = PlannerConfig(population=8, generations=3, f0=0.3, cr=0.5)
    res = run_optimizer("adaptive_de", small, small.bounds, planner=planner, rng=0)
    assert res.nfev == 8 * 4 and res.mutation[0] == pytest.approx(0.6)
    res = run_optimizer("grouped_pso", small, small.bounds, planner=planner, rng=0)
    assert res.nfev == 8 * 4
    with pytest.raises(ConfigError, match=r"grouped_pso\.f0"):
        run_optimizer("grouped_pso", small, small.bounds, f0=0.3)


# --------------------------------------------------------------------------- bad input


def test_unknown_optimizer_names_the_field_and_the_choices():
    with pytest.raises(ConfigError) as err:
        get_optimizer("simulated_annealing")
    assert err.value.field == "optimizer"
    for name in OPTIMIZERS:
        assert name in str(err.value)


@pytest.mark.parametrize("name", list(OPTIMIZERS))
@pytest.mark.parametrize("bounds", [[], [(1.0, 1.0)], [(2.0, 1.0)], [(0.0, np.inf)], "x"])
def test_empty_or_degenerate_bounds_are_rejected(name, bounds):
    with pytest.raises(ConfigError, match="bounds"):
        OPTIMIZERS[name](shifted_sphere, bounds, popsize=8, maxiter=2, rng=0)


def test_other_bad_arguments():
    with pytest.raises(ConfigError, match="popsize"):
        adaptive_de(shifted_sphere, BOUNDS_12, popsize=3)
    with pytest.raises(ConfigError, match="cr"):
        adaptive_de(shifted_sphere, BOUNDS_12, cr=1.5)
    with pytest.raises(ConfigError, match="rng"):
        adaptive_de(shifted_sphere, BOUNDS_12, rng="seed")
    with pytest.raises(ConfigError, match="uavs"):
        PlanObjective("small", uavs=0)


# ------------------------------------------------------------------------ presets (issue 12)


def test_presets_paper_is_the_planner_section_and_tuned_changes_only_f0_cr():
    from poc_env.agents.planning.optimizers import TUNED_DE, preset_settings

    pl = PlannerConfig()
    paper = preset_settings("paper", pl)
    assert paper == {"popsize": pl.population, "maxiter": pl.generations, "f0": pl.f0, "cr": pl.cr}
    assert (paper["f0"], paper["cr"]) == (0.2, 0.1)  # the paper's §6 constants
    tuned = preset_settings("tuned", pl)
    assert tuned == {**paper, **TUNED_DE}
    assert (tuned["f0"], tuned["cr"]) != (paper["f0"], paper["cr"])


@pytest.mark.parametrize("bad", ["bogus", "", "Paper", None, 1])
def test_unknown_preset_is_a_config_error(bad):
    from poc_env.agents.experiments.paper import run_experiment
    from poc_env.agents.planning.optimizers import preset_settings
    from poc_env.agents.planning.planner import make_plan

    for call in (
        lambda: preset_settings(bad, PlannerConfig()),
        lambda: make_plan("small", preset=bad, popsize=4, maxiter=1),
        lambda: run_experiment("fig22", quick=True, out="/nonexistent", preset=bad, echo=None),
    ):
        with pytest.raises(ConfigError, match=r"preset: got .*; allowed: paper or tuned"):
            call()


def test_cli_preset_bogus_is_a_clear_error(capsys, tmp_path):
    from poc_env.cli import main

    for argv in (
        ["plan", "--preset", "bogus", "--quiet", "--out", str(tmp_path / "p.json")],
        ["experiment", "fig22", "--quick", "--preset", "bogus", "--out", str(tmp_path / "e")],
    ):
        assert main(argv) == 2
        assert "error: preset: got 'bogus'; allowed: paper or tuned" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())  # nothing written


def test_tuned_preset_reaches_the_optimizer():
    """make_plan(preset="tuned") runs adaptive DE with TUNED_DE's F0 and CR: its plan is the
    one a direct call with those constants finds (same seed), not the paper preset's."""
    from poc_env.agents.planning.optimizers import TUNED_DE
    from poc_env.agents.planning.planner import make_plan

    obj = PlanObjective("small")
    budget = dict(popsize=12, maxiter=15)
    tuned = make_plan("small", preset="tuned", seed=3, **budget)
    paper = make_plan("small", preset="paper", seed=3, **budget)
    direct = adaptive_de(obj, obj.bounds, rng=3, **budget, **TUNED_DE)
    np.testing.assert_array_equal(tuned["x"], direct.x)
    assert not np.array_equal(paper["x"], tuned["x"])
    s = tuned["optimizer"]["settings"]
    assert (s["preset"], s["f0"], s["cr"]) == ("tuned", TUNED_DE["f0"], TUNED_DE["cr"])
    assert paper["optimizer"]["settings"]["preset"] == "paper"
