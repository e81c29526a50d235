"""What a compiled ``refine.leg_samples`` would save (issue 24, planning time with zones): a
script, not a test, and a proposal, not the planner's code.

The refinement (:mod:`poc_env.agents.planning.refine`) samples every candidate leg at a
quarter cell in numpy (:func:`~poc_env.agents.planning.refine.leg_samples`); with no-fly
zones ``paper_6_2`` is refined twice (two starts within ``REFINE_WITHIN``), and the
refinement is most of the zones' extra planning time (``python tests/planning/zones_ab.py
breakdown``). :func:`leg_samples` below is the same computation in one numba loop (the same
float operations in the same order, so the same samples bit for bit). ``CASE N``: plans
``CASE`` with the bench's 4 zones with numpy's and this sampling patched in, alternated ``N``
times in one process after a plan of each; prints both plans' waypoint digests (equal: the
same plan) and the CPU time medians and pair ratios.

Run from the repository root: ``OMP_NUM_THREADS=1 python tests/planning/leg_kernel_ab.py
paper_6_2 5``.
"""

from __future__ import annotations

import os
import statistics
import sys
import time

import numpy as np
from numba import njit

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))


@njit(cache=False)
def _samples(sx, sy, ex, ey, ox, oy, c, nx, ny, w, area):  # pragma: no cover - compiled
    n_legs = len(sx)
    m = np.empty(n_legs, np.int64)
    length = np.empty(n_legs)
    total = 0
    for i in range(n_legs):
        length[i] = np.hypot(ex[i] - sx[i], ey[i] - sy[i])
        k = np.ceil(4.0 * length[i] / c)
        m[i] = np.int64(k) if k > 1 else 1
        total += m[i]
    leg = np.empty(total, np.int64)
    cell = np.empty(total, np.int64)
    wt = np.empty(total)
    n = 0
    for i in range(n_legs):
        dx, dy = ex[i] - sx[i], ey[i] - sy[i]
        wi = w * length[i] / m[i] / area
        for j in range(m[i]):
            t = (j + 0.5) / m[i]
            col = np.int64(np.floor((sx[i] + t * dx - ox) / c))
            row = np.int64(np.floor((sy[i] + t * dy - oy) / c))
            if 0 <= col < nx and 0 <= row < ny:
                leg[n], cell[n], wt[n] = i, row * nx + col, wi
                n += 1
    return leg[:n], cell[:n], wt[:n]


def leg_samples(starts, ends, grid, w):
    """:func:`poc_env.agents.planning.refine.leg_samples`, compiled."""
    a = np.asarray(starts, dtype=float).reshape(-1, 2)
    b = np.asarray(ends, dtype=float).reshape(-1, 2)
    if not len(a):
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0)
    ox, oy = grid.origin_m
    return _samples(
        *(np.ascontiguousarray(v) for v in (a[:, 0], a[:, 1], b[:, 0], b[:, 1])),
        float(ox), float(oy), float(grid.cell_m), grid.nx, grid.ny, float(w),
        float(grid.cell_area_m2),
    )  # fmt: skip


def main(case: str, n: int) -> None:
    from zones_ab import _bench_case, _digest

    import poc_env.agents.planning.refine as refine
    from poc_env.agents.planning.allocation import make_allocation_plan

    sc, uavs = _bench_case(case)
    ways = {"numpy": refine.leg_samples, "compiled": leg_samples}
    cpu: dict[str, list[float]] = {k: [] for k in ways}
    print("load at start", os.getloadavg(), flush=True)
    for k, f in ways.items():
        refine.leg_samples = f  # type: ignore[assignment]
        plan = make_allocation_plan(sc, uavs=uavs)
        print(k, "digest", _digest(plan), "posc", plan["posc"], flush=True)
    for _ in range(n):
        for k, f in ways.items():
            refine.leg_samples = f  # type: ignore[assignment]
            c0 = time.process_time()
            make_allocation_plan(sc, uavs=uavs)
            cpu[k].append(time.process_time() - c0)
    med = {k: round(statistics.median(v), 3) for k, v in cpu.items()}
    pairs = [round(b / a, 3) for a, b in zip(cpu["numpy"], cpu["compiled"])]
    print(case, "CPU s medians", med, "pair ratios", pairs, "median", statistics.median(pairs))
    print("load at end", os.getloadavg(), flush=True)


if __name__ == "__main__":
    main(
        sys.argv[1] if len(sys.argv) > 1 else "paper_6_2",
        int(sys.argv[2]) if len(sys.argv) > 2 else 5,
    )
