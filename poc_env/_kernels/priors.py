"""Compiled prior maps: the Gaussian-mixture component's exponent and the sub-cell sums.

The kernels behind :func:`poc_env.theory.probability_map.gaussian_mixture`, which every
random-prior reset calls: one pass forms a component's ``-0.5 (u^2 + v^2)`` on the sub-cell
grid (numpy's ``exp`` follows, unchanged), one sums the sub-cells per cell as
:meth:`~poc_env.theory.probability_map.Grid.coarsen` does. Each floating-point operation is
the numpy formulation's, in its order (no fused or reordered arithmetic: numba compiles without
fast-math), so the maps are the same bit for bit; ``tests/theory/test_probability_map.py``
pins both to the numpy formulas.

A kernel module: imports nothing of the project (the cache rule, :mod:`poc_env._kernels`).
"""

from __future__ import annotations

from numba import njit

_jit = njit(cache=True, error_model="numpy")


@_jit
def mixture_exponent(xs, ys, mx, my, c, s, sx, sy, out):
    """Fill ``out (len(ys), len(xs))`` with ``-0.5 (u^2 + v^2)`` at the sub-cell centres
    ``(xs[i], ys[j])`` of one component (mean ``(mx, my)``, standard deviations ``(sx, sy)``,
    rotation cosine and sine ``c``, ``s``): ``u = (c dx + s dy) / sx``, ``v = (-s dx + c dy) /
    sy`` with ``(dx, dy) = (xs[i] - mx, ys[j] - my)``, each product and sum rounded as numpy
    rounds ``(c * dx + s * dy) / sx`` and ``(u * u + v * v) * -0.5`` element by element."""
    ny, nx = out.shape
    ns = -s
    for j in range(ny):
        dy = ys[j] - my
        sdy = s * dy
        cdy = c * dy
        row = out[j]
        for i in range(nx):
            dx = xs[i] - mx
            u = (c * dx + sdy) / sx
            v = (ns * dx + cdy) / sy
            row[i] = (u * u + v * v) * -0.5


@_jit
def coarsen(fine, s, out):
    """Fill ``out (ny, nx)`` with the sums of the ``s x s`` sub-cells of ``fine (ny s, nx s)``
    in numpy's order for ``Grid.coarsen`` (``1 < s < 8``, ``nx > 1``): ``0 +`` each of the
    cell's ``s`` sub-rows in turn, a sub-row summed from its first value in order."""
    ny, nx = out.shape
    for j in range(ny):
        acc = out[j]
        for i in range(nx):
            acc[i] = 0.0
        for a in range(s):
            row = fine[j * s + a]
            for i in range(nx):
                k = i * s
                r = row[k]
                for b in range(1, s):
                    r += row[k + b]
                acc[i] += r
