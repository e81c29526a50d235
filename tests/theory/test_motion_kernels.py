"""The fast paths of the filter's predict step (poc_env._kernels.motion) against the face-by-face
kernel they replace: bit for bit, so the registered Drift tasks keep their episodes."""

from __future__ import annotations

import numpy as np
import pytest

import poc_env._kernels.motion as kernel
from poc_env.config import TargetConfig
from poc_env.theory import motion


@pytest.mark.parametrize(
    ("shape", "n_sub", "diffusion"),
    [((4, 30, 40), 1, 50.0), ((3, 7, 5), 3, 300.0), ((2, 1, 9), 2, 0.0), ((2, 9, 1), 1, 10.0)],
)
def test_the_uniform_stencil_equals_the_face_kernel_bit_for_bit(shape, n_sub, diffusion):
    rng = np.random.default_rng(7)
    e = shape[0]
    mass = rng.random(shape)
    u = rng.uniform(-7.0, 7.0, e)
    v = rng.uniform(-7.0, 7.0, e)
    u[0] = 0.0  # a still env and a velocity along one axis
    v[-1] = 0.0
    want, got = mass.copy(), mass.copy()
    out_want, out_got = np.full(e, 0.25), np.full(e, 0.25)
    tau, h = 60.0 / n_sub, 2500.0
    u3, v3 = u[:, None, None].copy(), v[:, None, None].copy()
    for _ in range(3):
        kernel.advect_diffuse(want, u3, v3, diffusion, tau, h, n_sub, out_want)
        kernel.advect_diffuse_uniform(got, u, v, diffusion, tau, h, n_sub, out_got)
    assert not np.array_equal(want, mass)  # the step moved something
    np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(out_got, out_want)


def test_advect_diffuse_picks_the_stencil_for_uniform_velocities_and_matches_per_cell_ones():
    rng = np.random.default_rng(3)
    mass = rng.random((3, 12, 10))
    u, v = rng.uniform(-5, 5, 3), rng.uniform(-5, 5, 3)
    a, b = mass.copy(), mass.copy()
    out_a = motion.advect_diffuse(a, u[:, None, None], v[:, None, None], 20.0, 60.0, 500.0)
    full = np.ones((3, 12, 10))  # the same velocities given per cell: the face-by-face kernel
    out_b = motion.advect_diffuse(
        b, u[:, None, None] * full, v[:, None, None] * full, 20.0, 60.0, 500.0
    )
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(out_a, out_b)
    np.testing.assert_allclose(a.sum(axis=(1, 2)) + out_a, mass.sum(axis=(1, 2)), rtol=1e-12)


def test_the_fused_predict_equals_predict_then_move_targets_bit_for_bit():
    rng = np.random.default_rng(11)
    e, ny, nx, s, cell = 6, 8, 10, 2, 1000.0
    h = cell / s
    target = TargetConfig(model="drift", diffusion_m2_s=400.0)
    mot = motion.check(target, (ny, nx), 3600.0)
    belief = rng.random((e, ny * s, nx * s))
    drift = rng.uniform(-8.0, 8.0, (e, 2))
    origin = (-2000.0, 500.0)
    # targets inside, near each edge, and one already out of the map
    pos = np.column_stack([rng.uniform(-2000, 8000, e), rng.uniform(500, 8500, e)])
    pos[1] = (-1990.0, 4000.0)
    pos[2] = (7990.0, 4000.0)
    pos[3] = (3000.0, 8490.0)
    pos[4] = (-2500.0, 9000.0)
    out = np.zeros(e, dtype=bool)
    out[4] = True
    noise = rng.standard_normal((e, 3, 2))
    step = np.array([0, 1, 2, 5, 1, 9])  # beyond the noise's length: its last row
    mass_out = rng.random(e)

    b1, t1, o1, m1 = belief.copy(), pos.copy(), out.copy(), mass_out.copy()
    m1 += motion.predict(mot, b1, drift, 0.0, 60.0, h, s)
    idx = np.minimum(step, noise.shape[1] - 1)
    motion.move_targets(
        mot, t1, o1, drift, noise[np.arange(e), idx], 0.0, 60.0, origin, cell, (ny, nx)
    )
    b2, t2, o2, m2 = belief.copy(), pos.copy(), out.copy(), mass_out.copy()
    motion.predict_uniform(mot, b2, drift, m2, t2, o2, noise, step, 60.0, h, origin, cell, (ny, nx))
    assert o1[1] or o1[2] or o1[3]  # a target left the map this step
    for want, got in ((b1, b2), (m1, m2), (t1, t2), (o1, o2)):
        np.testing.assert_array_equal(got, want)


def test_the_fused_predict_refuses_a_gridded_field(tmp_path):
    path = tmp_path / "f.npy"
    np.save(path, np.zeros((2, 2, 2)))
    mot = motion.check(TargetConfig(model="drift", field_file=str(path)), (2, 2), 60.0)
    with pytest.raises(ValueError, match="gridded field"):
        motion.predict_uniform(
            mot, np.zeros((1, 2, 2)), np.zeros((1, 2)), np.zeros(1), np.zeros((1, 2)),
            np.zeros(1, dtype=bool), np.zeros((1, 1, 2)), np.zeros(1, dtype=int), 60.0, 1.0,
            (0.0, 0.0), 1.0, (2, 2),
        )  # fmt: skip
