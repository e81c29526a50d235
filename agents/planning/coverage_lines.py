"""The allocation start's lines (steps 2-3 of :mod:`poc_env.agents.planning.allocation`): a
coverage laid as nested layers of parallel lines along x, and regions chained nearest first.
Used by the allocation start and by the relaxation patches
(:mod:`poc_env.agents.planning.relax_patches`), which lay each UAV's own coverage the same way.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from poc_env.theory.probability_map import Grid

#: coverage laid at most (eq. 10: POD erf(sqrt(pi)/2 x 3) > 0.9999; more only adds lines).
COVER_CAP = 3.0


def layered_tracks(cov: np.ndarray, grid: Grid, w: float, levels: int) -> list[list[tuple]]:
    """Search lines per region: lists of (y, x_start, x_end, row) in boustrophedon order
    (coverage capped at :data:`COVER_CAP`)."""
    cov = np.minimum(cov, COVER_CAP)
    cmax = float(cov.max())
    if cmax <= 0:
        return []
    k = max(1, int(levels))
    delta = cmax / k
    h = w / cmax
    ox, oy = grid.origin_m
    c = grid.cell_m
    layer_of = np.clip(np.rint(cov / delta), 0, k).astype(int)  # layers crossing each cell
    labels, nreg = ndimage.label(layer_of > 0, structure=np.ones((3, 3)))
    nlines = int(np.floor(grid.ny * c / h))
    ys = oy + h * (np.arange(nlines) + 0.5)
    # runs of consecutive cells each line crosses: consecutive cells of positive coverage are
    # 8-connected, so a run lies in one region (its first cell's label)
    per_region: list[list[list[tuple]]] = [[] for _ in range(nreg + 1)]  # [label][line] runs
    for i, y in enumerate(ys):
        r = int((y - oy) // c)
        if r < 0 or r >= grid.ny:
            continue
        ok = layer_of[r] >= i % k + 1
        if not ok.any():
            continue
        edges = np.diff(np.concatenate([[0], ok.astype(int), [0]]))
        starts = np.flatnonzero(edges == 1)
        ends = np.flatnonzero(edges == -1)
        seen: set[int] = set()
        for a, b in zip(starts, ends, strict=True):
            reg = int(labels[r, a])
            if reg not in seen:  # this line's runs in the region, in order of x
                per_region[reg].append([])
                seen.add(reg)
            per_region[reg][-1].append((float(y), ox + a * c, ox + b * c, r))
    regions: list[list[tuple]] = []
    for reg in range(1, nreg + 1):
        # boustrophedon: line by line (in order of x on a line), direction alternating per line
        out = []
        flip = False
        for row in per_region[reg]:
            seq = reversed(row) if flip else row
            out += [(y, b, a, r) if flip else (y, a, b, r) for (y, a, b, r) in seq]
            flip = not flip
        if out:
            regions.append(out)
    return regions


def chain_regions(regions: list[list[tuple]], start: np.ndarray) -> list[tuple]:
    """Chain regions nearest-first from ``start`` (each may be flown reversed)."""
    left = list(regions)
    # each region's first point flown forward (its first line's start) and reversed (its last
    # line's end), as (x, y) rows: [2 i] forward, [2 i + 1] reversed
    ends = np.array([[(reg[0][1], reg[0][0]), (reg[-1][2], reg[-1][0])] for reg in left])
    ends = ends.reshape(-1, 2)
    pos = np.asarray(start, dtype=float)
    route: list[tuple] = []
    while left:
        j = int(np.argmin(np.hypot(ends[:, 0] - pos[0], ends[:, 1] - pos[1])))
        i, rev = divmod(j, 2)
        reg = left.pop(i)
        ends = np.delete(ends, [2 * i, 2 * i + 1], axis=0)
        seq = [(y, b, a, r) for (y, a, b, r) in reversed(reg)] if rev else reg
        route += seq
        pos = np.array([seq[-1][2], seq[-1][0]])
    return route
