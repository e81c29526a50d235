"""Excursions: routes ``take-off -> P -> Q -> landing`` whose transit legs are the search.

A candidate route for the coverage boxes (:mod:`poc_env.agents.planning.coverage_boxes`,
``PlanOptions.excursions``) for UAVs that can just reach the
mass (issue 24, docs/PLANNER.md, "Excursions"): on ``large_400`` the fields far from a blob
have a few tens of km of slack past its rim, the box search scores only the lines inside a box
(not the legs out and home), and their boxes are degenerate. An excursion flies out to a point
``P`` in the mass, across to ``Q`` and home; its three legs cross the mass on different
bearings, so field-mates fan out over the band they can reach.

Search: with the swarm's coverage ``C`` so far, a line through cell ``j`` gains about
``g_j = p_j (POD(C_j + W / c) - POD(C_j)) / c`` per metre (eq. 10 per cell, ``c`` the cell
side); a leg's gain is ``g`` summed along it (:func:`leg_gains`, half-cell samples). Every cell
centre the UAV can reach and come home from within 0.85 T is a ``P`` (the legs' times at the
plan's speeds), the ``top`` best ``P`` (out and home gain) are paired with every ``Q``
that keeps the time, and the ``exact`` best pairs (``PlanOptions.excursion_top``,
``excursion_exact``) by the summed leg gains (overlaps not
charged) are scored by the route's coverage (:func:`~poc_env.agents.planning.flight_rules.
path_coverage`) and cut to eq. 18 (:func:`~poc_env.agents.planning.coverage_boxes.cut_lines`:
``Q`` drawn back towards ``P`` until the route fits). Deterministic.
"""

from __future__ import annotations

import math

import numpy as np

from poc_env.agents.planning.flight_rules import Speeds
from poc_env.agents.planning.options import PlanOptions
from poc_env.theory.probability_map import Grid
from poc_env.theory.search_theory import pod_from_coverage


def leg_gains(a: np.ndarray, b: np.ndarray, rate: np.ndarray, grid: Grid) -> np.ndarray:
    """Gain of straight legs ``a -> b`` ((m, 2) each, or one point broadcast): the gain rate
    ``rate`` (per metre, grid-shaped) summed at half-cell samples along each leg; nothing
    outside the map counts."""
    a = np.broadcast_to(np.asarray(a, dtype=float), np.broadcast_shapes(np.shape(a), np.shape(b)))
    b = np.broadcast_to(np.asarray(b, dtype=float), a.shape)
    d = b - a
    length = np.hypot(d[:, 0], d[:, 1])
    c = grid.cell_m
    s = max(1, math.ceil(2.0 * float(length.max(initial=0.0)) / c))
    t = (np.arange(s) + 0.5) / s
    xy = a[:, None, :] + t[None, :, None] * d[:, None, :]  # (m, s, 2)
    ox, oy = grid.origin_m
    col = np.floor((xy[..., 0] - ox) / c).astype(np.int64)
    row = np.floor((xy[..., 1] - oy) / c).astype(np.int64)
    ok = (col >= 0) & (col < grid.nx) & (row >= 0) & (row < grid.ny)
    flat = np.where(ok, row * grid.nx + col, 0)
    vals = np.where(ok, rate.ravel()[flat], 0.0)
    return vals.sum(axis=1) * length / s


def excursion(
    prior: np.ndarray,
    cov: np.ndarray,
    grid: Grid,
    w: float,
    law: str,
    speeds: Speeds,
    takeoff: np.ndarray,
    landing: np.ndarray,
    budget: float,
    turn_rate: float,
    reserve: float,
    fits,
    score,
    cut,
    top: int = PlanOptions.excursion_top,
    exact: int = PlanOptions.excursion_exact,
) -> tuple[float, np.ndarray, np.ndarray]:
    """The best excursion (module docstring) of one UAV against the coverage ``cov``:
    (gain, waypoints [P, Q] or fewer, its coverage) by ``score(wps) -> (gain, coverage)``;
    ``fits(wps)`` says whether the route keeps eq. 18 and ``cut(wps, fits)`` cuts it until it
    does (:func:`~poc_env.agents.planning.coverage_boxes.cut_lines`). Gain 0 and no waypoints
    when no cell is reachable."""
    none = (0.0, np.zeros((0, 2)), np.zeros(grid.shape))
    c = grid.cell_m
    rate = prior * (pod_from_coverage(cov + w / c, law) - pod_from_coverage(cov, law)) / c
    ox, oy = grid.origin_m
    xs = ox + c * (np.arange(grid.nx) + 0.5)
    ys = oy + c * (np.arange(grid.ny) + 0.5)
    pts = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
    half_turn = math.pi / turn_rate
    t_out = np.hypot(*(pts - takeoff).T) / speeds.out
    t_home = np.hypot(*(pts - landing).T) / speeds.home
    left = budget - reserve - half_turn
    ok = t_out + t_home <= left
    if not ok.any():
        return none
    cand = pts[ok]
    g_out = leg_gains(takeoff[None, :], cand, rate, grid)
    g_home = leg_gains(cand, landing[None, :], rate, grid)
    order = np.argsort(-(g_out + g_home), kind="stable")[:top]
    pairs: list[tuple[float, int, int]] = []
    for i in order:
        p = cand[i]
        slack = left - half_turn - t_out[ok][i]
        t_pq = np.hypot(*(cand - p).T) / speeds.line
        good = np.flatnonzero(t_pq + t_home[ok] <= slack)
        if not len(good):
            continue
        val = g_out[i] + leg_gains(p[None, :], cand[good], rate, grid) + g_home[good]
        for j in np.argsort(-val, kind="stable")[:exact]:
            pairs.append((float(val[j]), int(i), int(good[j])))
    pairs.sort(key=lambda t: -t[0])
    best = none
    for _, i, j in pairs[:exact]:
        wps = np.vstack([cand[i], cand[j]])
        if not fits(wps):
            wps = cut(wps, fits)
        if not len(wps):
            continue
        val, cv = score(wps)
        if val > best[0]:
            best = (val, wps, cv)
    return best
