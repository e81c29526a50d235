"""The moving-target bound (poc_env.theory.moving_bound).

Brown's algorithm with its certificate equals a generic solver (SLSQP on every step's effort)
on small chains and on a gridded, time-varying field; the adjoint it uses is the filter's
transpose for any field, and its forward operator the filter; on a uniform drift it agrees with
the earlier adjoint (the scheme at ``-v``); with a target standing still it is the static
reach-aware bound's problem; the law slack makes ``F(C) <= 1 - exp(-kappa C) + delta`` hold.
"""

import numpy as np
import pytest
from scipy.optimize import minimize

from poc_env.agents.benchmarks.moving_bound import reversal_operators
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.theory import motion as motion_mod
from poc_env.theory.bound import reach_bound
from poc_env.theory.detection import detection_law
from poc_env.theory.moving_bound import (
    brown_optimum,
    law_slack,
    moving_bound,
    predict_operators,
)
from poc_env.theory.probability_map import Grid, build_prior


def _chain(rng, n):
    """A random sub-stochastic transition matrix (columns: from-cell; some mass leaves)."""
    p = rng.random((n, n)) ** 3
    return p / p.sum(axis=0) * rng.uniform(0.8, 1.0, n)


def _slsqp(m, a, mat, budgets, reach, starts=6, seed=0):
    """max 1 - E[exp(-sum_t c_t(X_t))] by SLSQP over every c_t (budgets (T,), reach (T, n));
    ``mat`` one transition matrix, or a list of one per step."""
    t_n, n = reach.shape
    mats = mat if isinstance(mat, list) else [mat] * t_n

    # N(c) = E[exp(-sum c)] including the paths that leave (never detected): track it exactly
    def nd(x):
        c = x.reshape(t_n, n)
        alpha = m.copy()
        gone = 0.0
        for t in range(t_n):
            before = alpha.sum()
            alpha = mats[t] @ alpha
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
    res = brown_optimum(m, a, lambda t, x: mat @ x, lambda t, y: mat.T @ y, budgets[None],
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
    one = brown_optimum(m, a, lambda t, x: mat @ x, lambda t, y: mat.T @ y, budgets[None],
                        reach[None], sweeps=1)  # fmt: skip
    assert one.upper >= ref - 1e-9


def _gridded(tmp_path, frames, dt_s=600.0, d=40.0, **extra):
    """``small`` drifting in the gridded field ``frames (T, 2, 8, 8)`` m/s, ``dt_s`` apart."""
    f = tmp_path / "v.npy"
    np.save(f, frames)
    over = {"target.model": "drift", "target.field_file": str(f), "target.diffusion_m2_s": d}
    if len(frames) > 1:
        over["target.field_dt_s"] = dt_s
    return load_scenario("small", {**over, **extra})


def _vortex(t_n, rng):
    """A time-varying, non-uniform current (T, 2, 8, 8) m/s: a turning swirl plus noise."""
    y, x = np.mgrid[0:8, 0:8] - 3.5
    out = []
    for k in range(t_n):
        a = 0.4 * k
        u = -y * np.cos(a) + x * np.sin(a)
        v = x * np.cos(a) + y * np.sin(a)
        out.append(np.stack([u, v]) * 0.35 + rng.normal(0.0, 0.3, (2, 8, 8)))
    return np.array(out)


@pytest.mark.parametrize("varying", [True, False])
@pytest.mark.parametrize("vel,d", [((3.0, -1.5), 0.0), ((-0.7, 2.2), 80.0), ((0.0, 0.0), 40.0)])
def test_adjoint_is_the_transpose_for_a_gridded_field(tmp_path, varying, vel, d):
    """<M_t x, y> = <x, M_t^T y> for every step of a gridded, time-varying field (plus a uniform
    current), and M_t x is the filter's predict (motion.predict, the environment's)."""
    rng = np.random.default_rng(1)
    sc = _gridded(tmp_path, _vortex(6 if varying else 1, rng), d=d)
    motion = motion_mod.check(sc.target, (8, 8), 3000.0, sc.map)
    s, dt, h = 3, 60.0, 200.0
    step, adjoint = predict_operators(motion, vel, dt, h, s, (24, 24))
    for t in (0, 7, 23, 49):  # between frames, on one, past the last (held)
        x, y = rng.random(576), rng.random(576)
        mx, mty = step(t, x), adjoint(t, y)
        assert float(mx @ y) == pytest.approx(float(x @ mty), rel=1e-12)
        ref = x.reshape(1, 24, 24).copy()
        motion_mod.predict(motion, ref, np.array([vel]), t * dt, dt, h, s)
        np.testing.assert_allclose(mx, ref.ravel(), rtol=1e-13, atol=1e-16)
    if varying:  # the field changes with time: the operators differ from step to step
        x = rng.random(576)
        assert np.abs(step(0, x) - step(23, x)).max() > 1e-3


@pytest.mark.parametrize("vel,d", [((3.0, -1.5), 0.0), ((-0.7, 2.2), 80.0), ((0.0, 0.0), 40.0)])
def test_adjoint_of_a_uniform_drift_is_the_reversed_velocity(vel, d):
    """For a uniform drift the sparse transpose equals the scheme run at -v (the adjoint used
    before gridded fields were covered) to rounding."""
    sc = load_scenario("small", {"target.model": "drift", "target.diffusion_m2_s": d})
    motion = motion_mod.check(sc.target, (8, 8), 1e4)
    rng = np.random.default_rng(1)
    y = rng.random((1, 24, 24))
    v = np.array([vel])
    _, adjoint = predict_operators(motion, vel, 60.0, 200.0, 3, (24, 24))
    rev = y.copy()
    motion_mod.predict(motion, rev, -v, 0.0, 60.0, 200.0, 3)
    np.testing.assert_allclose(adjoint(0, y.ravel()), rev.ravel(), rtol=1e-13, atol=1e-16)


@pytest.mark.parametrize("law", ["inverse_cube", "exponential"])
def test_uniform_drift_bound_unchanged_by_the_sparse_adjoint(monkeypatch, law):
    """The bound of a uniform drift with the sparse operators agrees to 1e-12 with the earlier
    velocity-reversal operators (one path now; the reference kept here)."""
    import poc_env.theory.moving_bound as mb

    over = {"target.model": "drift", "target.diffusion_m2_s": 50.0, "sensor.law": law}
    sc = load_scenario("small", over)
    prior = build_prior(sc.map)
    fine = np.repeat(np.repeat(prior, 2, axis=0), 2, axis=1) / 4.0
    vel = (5.5, -2.0)
    new = moving_bound(sc, fine, vel, s=2, sweeps=2)
    monkeypatch.setattr(mb, "predict_operators", reversal_operators)
    old = moving_bound(sc, fine, vel, s=2, sweeps=2)
    assert new.upper == pytest.approx(old.upper, abs=1e-12)
    assert new.pos == pytest.approx(old.pos, abs=1e-12)


def test_constant_gridded_field_is_the_uniform_drift(tmp_path):
    """A gridded field holding one velocity everywhere gives the uniform drift's bound."""
    vel = np.array([2.5, -1.0])
    frames = np.broadcast_to(vel[None, :, None, None], (1, 2, 8, 8)).copy()
    sc = _gridded(tmp_path, frames)
    plain = load_scenario("small", {"target.model": "drift", "target.diffusion_m2_s": 40.0})
    prior = build_prior(sc.map)
    fine = np.repeat(np.repeat(prior, 2, axis=0), 2, axis=1) / 4.0
    got = moving_bound(sc, fine, (0.0, 0.0), s=2, sweeps=2)
    ref = moving_bound(plain, fine, vel, s=2, sweeps=2)
    assert got.upper == pytest.approx(ref.upper, abs=1e-12)
    drift = moving_bound(plain, fine, (0.0, 0.0), s=2, sweeps=2)
    assert abs(drift.upper - ref.upper) > 1e-4  # the velocity matters: the check can fail


@pytest.mark.parametrize("seed", range(3))
def test_brown_equals_slsqp_on_a_gridded_time_varying_field(seed):
    """On a 2 x 3-cell map in a time-varying, non-uniform current with diffusion: Brown's
    optimum and certificate with the filter's operators against SLSQP on the same matrices."""
    rng = np.random.default_rng(seed)
    t_n, dt, h = 4, 300.0, 1000.0
    frames = rng.normal(0.0, 1.2, (t_n, 2, 2, 3))
    motion = motion_mod.Motion(
        model=motion_mod.MODELS["drift"], diffusion=150.0, current=(0.0, 0.0),
        random_current=0.0, wind=(0.0, 0.0), leeway=None,
        field=motion_mod.VelocityField(frames, dt),
    )  # fmt: skip
    step, adjoint = predict_operators(motion, (0.3, -0.2), dt, h, 1, (2, 3))
    eye = np.eye(6)
    mats = [np.stack([step(t, e) for e in eye], axis=1) for t in range(t_n)]
    assert len({m.tobytes() for m in mats}) == t_n  # a different operator each step
    m = rng.random(6)
    m /= m.sum()
    a = np.full(6, h * h) / 1e6
    budgets = rng.uniform(0.5, 3.0, t_n)
    reach = rng.random((t_n, 6)) < 0.8
    reach[:, 0] = True
    res = brown_optimum(m, a, step, adjoint, budgets[None], reach[None], sweeps=60)
    ref = _slsqp(m, a, mats, budgets, reach, seed=seed)
    assert res.upper >= ref - 1e-9
    assert res.pos == pytest.approx(ref, abs=2e-6)
    assert res.gap < 1e-4


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


@pytest.mark.parametrize(
    "over",
    [
        {"target.model": "diffusion", "target.diffusion_m2_s": 300.0},
        {"target.model": "leeway", "target.wind_kmh": [40.0, 10.0],
         "target.leeway_class": "life_raft_no_ballast"},
    ],
)  # fmt: skip
def test_diffusion_and_leeway_are_covered(over):
    """Diffusion only (v = 0) and leeway in a uniform wind (the episode's drift velocity, its
    crosswind side drawn at reset) are bounded: the motion changes the bound (the predict is
    not skipped), and leeway's is the uniform drift's of the same velocity and diffusion."""
    sc = load_scenario("small", {**over, "sensor.law": "exponential"})
    prior = build_prior(sc.map)
    fine = np.repeat(np.repeat(prior, 2, axis=0), 2, axis=1) / 4.0
    motion = motion_mod.check(sc.target, (8, 8), sc.horizon_steps * sc.episode.dt_s)
    vel = motion.draw(np.random.default_rng(0))
    got = moving_bound(sc, fine, vel, s=2, sweeps=3)
    still = moving_bound(load_scenario("small", {"sensor.law": "exponential"}), fine,
                         (0.0, 0.0), s=2, sweeps=3)  # fmt: skip
    assert got.pos <= got.upper <= 1.0
    assert abs(got.upper - still.upper) > 1e-3
    if over["target.model"] == "leeway":
        assert np.hypot(*vel) > 0.3  # the leeway of a raft in 40 km/h of wind
        drift = load_scenario("small", {"target.model": "drift", "sensor.law": "exponential",
                                        "target.diffusion_m2_s": motion.diffusion})  # fmt: skip
        assert moving_bound(drift, fine, vel, s=2, sweeps=3).upper == got.upper


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


def test_a_matrix_that_is_not_the_filter_is_an_error(monkeypatch):
    """Each assembled matrix is checked against the filter's predict: a motion the matrix does
    not reproduce (here: a stand-in that moves the mass upstream) is refused, not bounded."""
    from scipy import sparse

    sc = load_scenario("small", {"target.model": "drift", "target.current_kmh": [40.0, 0.0]})
    fine = np.full((16, 16), 1.0 / 256)
    moving_bound(sc, fine, (11.0, 0.0), s=2, sweeps=1)  # the filter's matrix passes
    real = motion_mod.substep_matrix

    def upstream(*args, **kw):
        mat, n = real(*args, **kw)
        return sparse.csr_array(mat.T), n

    monkeypatch.setattr(motion_mod, "substep_matrix", upstream)
    with pytest.raises(ValueError, match="not covered"):
        moving_bound(sc, fine, (11.0, 0.0), s=2, sweeps=1)


def test_a_matrix_reused_at_another_step_is_checked_there(monkeypatch, tmp_path):
    """The check runs at every step, not only when a matrix is built: if the cache took two
    slices of a time-varying field for one (here: every key made equal), the step where the
    reused matrix is not the filter's is refused."""
    import types

    import poc_env.theory.moving_bound as mb

    sc = _gridded(tmp_path, _vortex(6, np.random.default_rng(2)), d=20.0)
    fine = np.full((16, 16), 1.0 / 256)
    moving_bound(sc, fine, (0.0, 0.0), s=2, sweeps=1)
    same = types.SimpleNamespace(digest=lambda: b"one key")
    monkeypatch.setattr(mb.hashlib, "sha1", lambda data: same)
    with pytest.raises(ValueError, match="not covered"):
        moving_bound(sc, fine, (0.0, 0.0), s=2, sweeps=1)
