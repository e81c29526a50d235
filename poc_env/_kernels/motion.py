"""Compiled predict step of a moving target's belief (:mod:`poc_env.theory.motion`).

One finite-volume pass per sub-step and env: upwind advective and centred diffusive fluxes
through every face from the sub-step's starting masses, each flux taken from one cell and given
to its neighbour, the fluxes through the map's edge summed into the mass that left. Imports
nothing of the project (the cache rule of :mod:`poc_env._kernels`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

_jit = njit(cache=True, error_model="numpy")


@_jit
def substeps(u_max, v_max, diffusion, dt, h):
    """Sub-steps of one ``dt`` keeping ``(|u| + |v|) tau / h + 4 D tau / h^2 <= 1``."""
    rate = (u_max + v_max) / h + 4.0 * diffusion / (h * h)
    return max(1, math.ceil(rate * dt - 1e-9))


@_jit
def _face(vel, k, j, i, j2, i2):
    """Mean of two cells' velocities (``vel`` (E, 1 | NY, 1 | NX): uniform or per cell)."""
    fy, fx = vel.shape[1] > 1, vel.shape[2] > 1
    a = vel[k, j if fy else 0, i if fx else 0]
    b = vel[k, j2 if fy else 0, i2 if fx else 0]
    return 0.5 * (a + b)


@_jit
def advect_diffuse(mass, u, v, diffusion, tau, h, n_sub, out):
    """``n_sub`` sub-steps of ``tau`` s on ``mass (E, NY, NX)`` (in place) with cell velocities
    ``u, v`` (E, 1 | NY, 1 | NX) m/s and diffusion ``D`` on cells of side ``h``; adds the mass
    leaving the map to ``out (E,)``."""
    e, ny, nx = mass.shape
    c = tau / h
    kd = diffusion * tau / (h * h)
    tmp = np.empty((ny, nx))
    for k in range(e):
        for _ in range(n_sub):
            tmp[:, :] = mass[k]
            for j in range(ny):
                for i in range(nx + 1):  # face between cells i - 1 and i
                    il = i - 1 if i > 0 else 0
                    ir = i if i < nx else nx - 1
                    uf = _face(u, k, j, il, j, ir)
                    left = tmp[j, i - 1] if i > 0 else 0.0
                    right = tmp[j, i] if i < nx else 0.0
                    f = (max(uf, 0.0) * c + kd) * left + (min(uf, 0.0) * c - kd) * right
                    if i > 0:
                        mass[k, j, i - 1] -= f
                    else:
                        out[k] -= f
                    if i < nx:
                        mass[k, j, i] += f
                    else:
                        out[k] += f
            for j in range(ny + 1):  # face between rows j - 1 and j
                jl = j - 1 if j > 0 else 0
                jr = j if j < ny else ny - 1
                for i in range(nx):
                    vf = _face(v, k, jl, i, jr, i)
                    low = tmp[j - 1, i] if j > 0 else 0.0
                    high = tmp[j, i] if j < ny else 0.0
                    f = (max(vf, 0.0) * c + kd) * low + (min(vf, 0.0) * c - kd) * high
                    if j > 0:
                        mass[k, j - 1, i] -= f
                    else:
                        out[k] -= f
                    if j < ny:
                        mass[k, j, i] += f
                    else:
                        out[k] += f


@_jit
def advect_diffuse_uniform(mass, u, v, diffusion, tau, h, n_sub, out):
    """:func:`advect_diffuse` for one velocity per env (``u, v`` (E,) m/s), bit-identical to
    it: the same fluxes in the same order of operations, as a branch-free five-point stencil
    over three rotating row buffers padded with zeros, which the compiler vectorises.

    A cell's new mass is ``((m + f_left) - f_right) + g_low - g_high``, each face flux
    ``f = a L + b R`` with ``a = max(u, 0) c + k``, ``b = min(u, 0) c - k``, ``c = tau / h``,
    ``k = D tau / h^2``. The mass leaving through the edge is summed face by face in
    :func:`advect_diffuse`'s order (rows' west then east faces, then the south row, then the
    north row)."""
    e, ny, nx = mass.shape
    c = tau / h
    kd = diffusion * tau / (h * h)
    # the sub-step's starting rows j - 1, j, j + 1, a zero either side (zero rows off the map);
    # rotated row by row, so the map is read once and written once
    ra = np.zeros(nx + 2)
    rb = np.zeros(nx + 2)
    rc = np.zeros(nx + 2)
    first = np.zeros(nx)  # the starting row 0 (its south faces are summed last)
    for k in range(e):
        ax = max(u[k], 0.0) * c + kd
        bx = min(u[k], 0.0) * c - kd
        ay = max(v[k], 0.0) * c + kd
        by = min(v[k], 0.0) * c - kd
        m = mass[k]
        for _ in range(n_sub):
            acc = out[k]
            lo, mid, hi = ra, rb, rc
            lo[:] = 0.0
            for i in range(nx):
                mid[i + 1] = m[0, i]
                first[i] = m[0, i]
            for j in range(ny):
                # the row's west and east edge faces, in the face kernel's order
                acc -= ax * 0.0 + bx * mid[1]
                acc += ax * mid[nx] + bx * 0.0
                if j + 1 < ny:
                    for i in range(nx):
                        hi[i + 1] = m[j + 1, i]
                else:
                    hi[:] = 0.0
                for i in range(nx):
                    mc = mid[i + 1]
                    fl = ax * mid[i] + bx * mc
                    fr = ax * mc + bx * mid[i + 2]
                    gl = ay * lo[i + 1] + by * mc
                    gh = ay * mc + by * hi[i + 1]
                    m[j, i] = (((mc + fl) - fr) + gl) - gh
                lo, mid, hi = mid, hi, lo
            # then the south edge (the starting row 0) and the north edge (the starting last
            # row, now in lo)
            for i in range(nx):
                acc -= ay * 0.0 + by * first[i]
            for i in range(nx):
                acc += ay * lo[i + 1] + by * 0.0
            out[k] = acc


@_jit
def predict_uniform(
    mass, drift, diffusion, dt, h, mass_out, target, target_out, noise, step, x0, y0, x1, y1
):
    """The whole predict step of the filter for one velocity per env (``drift`` (E, 2) m/s,
    east and north), in one call: the belief ``mass (E, NY, NX)`` moved over ``dt`` in
    :func:`substeps` sub-steps of the batch's largest speeds (:func:`advect_diffuse_uniform`),
    the mass leaving the map added to ``mass_out (E,)``, and each hidden target ``target (E,
    2)`` still inside the map ``[x0, x1) x [y0, y1)`` moved by ``drift dt + sqrt(2 D dt)
    noise[k, min(step, T - 1)]`` (``target_out`` set for a target that leaves)."""
    e = mass.shape[0]
    u_max = 0.0
    v_max = 0.0
    for k in range(e):
        u_max = max(u_max, abs(drift[k, 0]))
        v_max = max(v_max, abs(drift[k, 1]))
    n = substeps(u_max, v_max, diffusion, dt, h)
    out = np.zeros(e)
    advect_diffuse_uniform(mass, drift[:, 0], drift[:, 1], diffusion, dt / n, h, n, out)
    sd = math.sqrt(2.0 * diffusion * dt)
    last = noise.shape[1] - 1
    for k in range(e):
        mass_out[k] += out[k]
        s = min(step[k], last)
        if not target_out[k]:
            target[k, 0] += drift[k, 0] * dt + sd * noise[k, s, 0]
            target[k, 1] += drift[k, 1] * dt + sd * noise[k, s, 1]
        x = target[k, 0]
        y = target[k, 1]
        if x < x0 or x >= x1 or y < y0 or y >= y1:
            target_out[k] = True


@_jit
def csr_apply(indptr, indices, data, x, out):
    """``out[k] = A @ x[k]`` for every env ``k``: ``A`` the CSR matrix ``(indptr, indices,
    data)`` (n, n), ``x, out (E, n)`` (the particles' transition,
    :func:`poc_env.theory.particles.predict`)."""
    e, n = x.shape
    for k in range(e):
        for r in range(n):
            acc = 0.0
            for p in range(indptr[r], indptr[r + 1]):
                acc += data[p] * x[k, indices[p]]
            out[k, r] = acc
