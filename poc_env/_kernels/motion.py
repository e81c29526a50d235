"""Compiled predict step of a moving target's belief (:mod:`poc_env.theory.motion`).

One finite-volume pass per sub-step and env: upwind advective and centred diffusive fluxes
through every face from the sub-step's starting masses, each flux taken from one cell and given
to its neighbour, the fluxes through the map's edge summed into the mass that left. Imports
nothing of the project (the cache rule of :mod:`poc_env._kernels`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

_jit = njit(cache=True, error_model="numpy")


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
