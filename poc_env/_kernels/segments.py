"""Segments against polygon edges, for the zone router (:mod:`poc_env.sim.routing`).

:func:`edge_contacts` sorts straight segments by whether they touch a polygon's boundary:
``0`` certainly no contact with any edge, ``1`` certainly a proper crossing of an edge, ``2``
not certain (a touch, a collinear overlap, or orientations too close to zero for floating
point). Every sign it relies on is certified by a forward error bound far above the exact
bound of the float orientation determinant (Shewchuk's ``(3 + 16 eps) eps`` of the sum of the
two products' magnitudes), so a ``0`` or ``1`` is the exact answer for the double-precision
coordinates, the one GEOS's robust predicates give; the caller settles ``2`` with shapely.

A kernel module under the cache rule of :mod:`poc_env._kernels`: it imports nothing of the
project.
"""

from __future__ import annotations

from numba import njit

_jit = njit(cache=True, error_model="numpy")

#: relative bound on the float orientation determinant's error (certified signs only beyond
#: it); the exact bound is about 3.3e-16.
_REL = 1e-12


@njit(cache=True, error_model="numpy", inline="always")
def _orient(ax, ay, bx, by, cx, cy):
    """The side of ``c`` from the line ``a -> b``: 1 left, -1 right, 0 not certain."""
    left = (bx - ax) * (cy - ay)
    right = (by - ay) * (cx - ax)
    d = left - right
    bound = _REL * (abs(left) + abs(right))
    if d > bound:
        return 1
    if d < -bound:
        return -1
    return 0


@_jit
def edge_contacts(ax, ay, bx, by, ex0, ey0, ex1, ey1, rings, boxes, out):
    """``out[i]``: how segment ``(ax[i], ay[i]) -> (bx[i], by[i])`` meets the edges
    ``(ex0[j], ey0[j]) -> (ex1[j], ey1[j])`` (module doc: 0 none, 1 a proper crossing, 2 not
    certain). The edges are grouped by ring: ring ``r`` holds edges ``rings[r]`` to
    ``rings[r + 1] - 1`` inside the box ``boxes[r] = (x0, y0, x1, y1)``. A zero-length segment
    is 2 unless its point lies outside every ring's box."""
    for i in range(len(ax)):
        px, py, qx, qy = ax[i], ay[i], bx[i], by[i]
        sx0, sx1 = min(px, qx), max(px, qx)
        sy0, sy1 = min(py, qy), max(py, qy)
        point = px == qx and py == qy
        state = 0
        for r in range(len(rings) - 1):
            if boxes[r, 2] < sx0 or boxes[r, 0] > sx1 or boxes[r, 3] < sy0 or boxes[r, 1] > sy1:
                continue
            if point:
                state = 2
                continue
            for j in range(rings[r], rings[r + 1]):
                ux, uy, vx, vy = ex0[j], ey0[j], ex1[j], ey1[j]
                if max(ux, vx) < sx0 or min(ux, vx) > sx1 or max(uy, vy) < sy0 or min(uy, vy) > sy1:
                    continue
                o1 = _orient(px, py, qx, qy, ux, uy)
                o2 = _orient(px, py, qx, qy, vx, vy)
                if o1 != 0 and o1 == o2:
                    continue  # the edge lies strictly on one side of the segment's line
                o3 = _orient(ux, uy, vx, vy, px, py)
                o4 = _orient(ux, uy, vx, vy, qx, qy)
                if o3 != 0 and o3 == o4:
                    continue  # the segment lies strictly on one side of the edge's line
                if o1 != 0 and o2 != 0 and o3 != 0 and o4 != 0:
                    state = 1  # o1 = -o2 and o3 = -o4: a proper crossing
                    break
                state = 2
            if state == 1:
                break
        out[i] = state
