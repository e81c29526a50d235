"""The physical optimum: the most POS any plan could reach with a given total effort.

For a prior (cell masses ``m_j``, cell areas ``a_j``), a detection law ``POD(C)`` as a function
of the coverage ``C`` (:func:`poc_env.theory.search_theory.pod_from_coverage`) and a total effort
``Z = W x track length`` (m^2), the Koopman/Stone optimal allocation solves

    maximise  sum_j m_j POD(C_j)   subject to   sum_j a_j C_j = Z,  C_j >= 0.

The objective is concave, so the KKT conditions are sufficient: every searched cell has the same
marginal return ``(m_j / a_j) POD'(C_j) = lambda``. Each law's entry in the table
(:mod:`poc_env.theory.detection`) gives that coverage as ``optimal_coverage(g)`` with
``g = ln(m_j / (a_j lambda))`` for ``m_j / a_j > lambda`` (0 elsewhere): for the inverse-cube law
(POD' = exp(-pi C^2 / 4)) ``C_j = sqrt(4/pi g)``, for the exponential law ``C_j = g``;
``lambda`` is found by bisection so that the effort is spent exactly. A law without one (the
definite-range law, linear up to C = 1) fills the densest cells first. No plan with the same
effort and law can beat this value: every plan report prints it beside its POS.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from poc_env.errors import ConfigError, check_positive
from poc_env.theory.detection import DetectionLaw, detection_law
from poc_env.theory.search_theory import pod_from_coverage


@dataclass(frozen=True)
class Bound:
    """Result of :func:`physical_optimum`: the POS bound and the optimal coverage per cell."""

    pos: float
    coverage: np.ndarray
    multiplier: float
    effort_m2: float
    law: str


def _coverage_at(lam: float, density: np.ndarray, law: DetectionLaw) -> np.ndarray:
    """The KKT coverage of every cell for the multiplier ``lam`` (the law's table entry)."""
    assert law.optimal_coverage is not None
    with np.errstate(divide="ignore"):
        g = np.log(np.where(density > 0, density, 1e-300) / lam)
    return law.optimal_coverage(np.maximum(g, 0.0))


def physical_optimum(prior, cell_area_m2, effort_m2: float, law: str = "inverse_cube") -> Bound:
    """Maximum POS reachable with ``effort_m2`` of sweep-width x track length (see module doc).

    ``prior`` is any array of cell masses; ``cell_area_m2`` a scalar or an array of its shape.
    """
    entry = detection_law(law)
    law = entry.name
    m = np.asarray(prior, dtype=float)
    if m.size == 0 or not np.all(np.isfinite(m)) or np.any(m < 0):
        raise ConfigError("prior", "array", "finite cell masses >= 0")
    effort = check_positive("effort_m2", effort_m2, allow_zero=True)
    area = np.broadcast_to(np.asarray(cell_area_m2, dtype=float), m.shape)
    if np.any(area <= 0):
        raise ConfigError("cell_area_m2", "array", "cell areas > 0")
    density = m / area
    if effort == 0 or not np.any(m > 0):
        return Bound(0.0, np.zeros_like(m), float(density.max(initial=0)), effort, law)
    if entry.optimal_coverage is None:  # POD linear up to saturation: densest cells first
        order = np.argsort(-density, axis=None, kind="stable")
        a = area.ravel()[order]
        filled = np.cumsum(a)
        cov = np.zeros(m.size)
        full = filled <= effort
        cov[order[full]] = 1.0
        k = int(full.sum())
        if k < m.size:
            cov[order[k]] = (effort - (filled[k - 1] if k else 0.0)) / a[k]
        cov_map = cov.reshape(m.shape)
        return Bound(
            float(np.sum(m * cov_map)),
            cov_map,
            float(density.ravel()[order[min(k, m.size - 1)]]),
            effort,
            law,
        )
    # bisection on log(lambda): spent effort decreases monotonically in lambda
    lo = np.log(density[density > 0].min()) - 60.0
    hi = np.log(density.max())
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        spent = float(np.sum(area * _coverage_at(np.exp(mid), density, entry)))
        if spent > effort:
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-15:
            break
    lam = np.exp(0.5 * (lo + hi))
    cov = _coverage_at(lam, density, entry)
    spent = float(np.sum(area * cov))
    if spent > 0:  # spend exactly the effort (removes the last bisection rounding)
        cov = cov * (effort / spent)
    value = float(np.sum(m * pod_from_coverage(cov, law)))
    return Bound(value, cov, float(lam), effort, law)
