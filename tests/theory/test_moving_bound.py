"""The moving-target bound (poc_env.theory.moving_bound).

Brown's algorithm with its certificate equals a generic solver (SLSQP on every step's effort)
on small chains; the adjoint it uses is the filter's transpose; with a target standing still it
is the static reach-aware bound's problem; the law slack makes ``F(C) <= 1 - exp(-kappa C) +
delta`` hold.
"""

import numpy as np
import pytest
from scipy.optimize import minimize

from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.theory import motion as motion_mod
from poc_env.theory.bound import reach_bound
from poc_env.theory.detection import detection_law
from poc_env.theory.moving_bound import brown_optimum, law_slack, moving_bound
from poc_env.theory.probability_map import Grid, build_prior


def _chain(rng, n):
    """A random sub-stochastic transition matrix (columns: from-cell; some mass leaves)."""
    p = rng.random((n, n)) ** 3
    return p / p.sum(axis=0) * rng.uniform(0.8, 1.0, n)


def _slsqp(m, a, mat, budgets, reach, starts=6, seed=0):
    """max 1 - E[exp(-sum_t c_t(X_t))] by SLSQP over every c_t (budgets (T,), reach (T, n))."""
    t_n, n = reach.shape

    # N(c) = E[exp(-sum c)] including the paths that leave (never detected): track it exactly
    def nd(x):
        c = x.reshape(t_n, n)
        alpha = m.copy()
        gone = 0.0
        for t in range(t_n):
            before = alpha.sum()
            alpha = mat @ alpha
            gone += before - alpha.sum()
            alpha = alpha * np.exp(-c[t])
        return alpha.sum() + gone

    rows = np.zeros((t_n, t_n * n))
    for t in range(t_n):
        rows[t, t * n : (t + 1) * n] = a
    cons = {"type": "ineq", "fun": lambda x: budgets - rows @ x, "jac": lambda x: -rows}
    bounds = [(0.0, 0.0 if not r else None) for r in reach.ravel()]
    rng = np.random.default_rng(seed)
    best = np.inf
    for _ in range(starts):
        x0 = rng.random(t_n * n) * reach.ravel()
        x0 *= np.min(budgets / np.maximum(rows @ x0, 1e-12))
        r = minimize(nd, x0, method="SLSQP", bounds=bounds, constraints=[cons],
                     options={"maxiter": 500, "ftol": 1e-12})  # fmt: skip
        if r.success or r.status == 9:
            best = min(best, float(nd(r.x)))
    return float(m.sum()) - best


@pytest.mark.parametrize("seed", range(5))
def test_brown_equals_slsqp_on_small_chains(seed):
    rng = np.random.default_rng(seed)
    n, t_n = 5, 4
    m = rng.random(n)
    m /= m.sum()
    a = rng.uniform(0.5, 2.0, n)
    mat = _chain(rng, n)
    budgets = rng.uniform(0.5, 3.0, t_n)
    reach = rng.random((t_n, n)) < 0.8
    reach[:, 0] = True
    res = brown_optimum(m, a, lambda x: mat @ x, lambda y: mat.T @ y, budgets[None],
                        reach[None], sweeps=60)  # fmt: skip
    ref = _slsqp(m, a, mat, budgets, reach, seed=seed)
    assert res.upper >= ref - 1e-9  # the certificate is an upper bound
    assert res.pos == pytest.approx(ref, abs=2e-6)  # Brown's sweeps reach the optimum
    assert res.gap < 1e-4


def test_certificate_holds_at_a_poor_point():
    """One sweep only: the effort found is worse, the certificate still bounds the optimum."""
    rng = np.random.default_rng(7)
    n, t_n = 6, 5
    m = rng.random(n)
    m /= m.sum()
    a = np.ones(n)
    mat = _chain(rng, n)
    budgets = np.full(t_n, 2.0)
    reach = np.ones((t_n, n), dtype=bool)
    ref = _slsqp(m, a, mat, budgets, reach)
    one = brown_optimum(m, a, lambda x: mat @ x, lambda y: mat.T @ y, budgets[None],
                        reach[None], sweeps=1)  # fmt: skip
    assert one.upper >= ref - 1e-9


@pytest.mark.parametrize("vel,d", [((3.0, -1.5), 0.0), ((-0.7, 2.2), 80.0), ((0.0, 0.0), 40.0)])
def test_adjoint_is_the_reversed_velocity(vel, d):
    """<M x, y> = <x, M^T y> with M^T the same scheme at -v (module docstring)."""
    sc = load_scenario("small", {"target.model": "drift", "target.diffusion_m2_s": d})
    motion = motion_mod.check(sc.target, (8, 8), 1e4)
    rng = np.random.default_rng(1)
    x, y = rng.random((1, 24, 24)), rng.random((1, 24, 24))
    v = np.array([vel])
    mx = x.copy()
    motion_mod.predict(motion, mx, v, 0.0, 60.0, 200.0, 3)
    mty = y.copy()
    motion_mod.predict(motion, mty, -v, 0.0, 60.0, 200.0, 3)
    assert float((mx * y).sum()) == pytest.approx(float((x * mty).sum()), rel=1e-12)


def test_static_target_is_the_reach_bound():
    """A target that stands still (exponential law, the environment's exact model): the moving
    bound is a relaxation of the reach-aware bound's problem (its reach is checked at each
    step's end), so at least its allocation's value, and close to its certificate."""
    sc = load_scenario("small", {"sensor.law": "exponential"})
    grid = Grid.from_config(sc.map)
    prior = build_prior(sc.map)
    s = 2
    fine = np.repeat(np.repeat(prior, s, axis=0), s, axis=1) / (s * s)
    mb = moving_bound(sc, fine, (0.0, 0.0), s=s, sweeps=8)
    rb = reach_bound(sc, prior)
    assert mb.upper >= rb.pos - 1e-9
    assert mb.upper <= rb.upper + 0.02  # a step of reach at most: dt v_max of 1.5 h of transit
    assert grid.shape == prior.shape


@pytest.mark.parametrize("law", ["inverse_cube", "definite_range", "exponential"])
@pytest.mark.parametrize("kappa", [1.0, 1.5, 2.0, 3.0])
def test_law_slack_dominates(law, kappa):
    entry = detection_law(law)
    delta = law_slack(law, kappa)
    c = np.concatenate([np.random.default_rng(0).uniform(0, 50, 200_000), np.linspace(0, 3, 7919)])
    assert np.all(entry.pod(c) <= 1.0 - np.exp(-kappa * c) + delta + 1e-15)
    if law == "exponential" and kappa == 1.0:
        assert delta == 0.0


def test_gridded_field_refused(tmp_path):
    f = tmp_path / "v.npy"
    np.save(f, np.zeros((2, 8, 8)))
    sc = load_scenario("small", {"target.model": "drift", "target.field_file": str(f)})
    with pytest.raises(ConfigError, match=r"target\.field_file"):
        moving_bound(sc, np.full((16, 16), 1 / 256), (0.0, 0.0), s=2)


def test_bad_prior_shape_refused():
    sc = load_scenario("small", {"target.model": "drift"})
    with pytest.raises(ConfigError, match="prior_fine"):
        moving_bound(sc, np.ones((5, 7)), (0.0, 0.0), s=2)


@pytest.mark.parametrize("seed", range(6))
def test_water_fill_is_physical_optimum(seed):
    """The closed-form exponential water-filling equals the static bound's root finding."""
    from poc_env.theory.bound import physical_optimum
    from poc_env.theory.moving_bound import water_fill

    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 300))
    w = rng.random(n) ** 4 + 1e-12
    a = rng.uniform(0.5, 2.0, n)
    effort = float(rng.uniform(1e-3, 3.0) * n ** rng.uniform(0, 1))
    ref = physical_optimum(w, a, effort, "exponential").coverage
    got = water_fill(w, a, effort)
    np.testing.assert_allclose(got, ref, atol=1e-9)
    assert float(a @ got) == pytest.approx(effort, rel=1e-12)
