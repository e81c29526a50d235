"""The table of detection laws: every law-specific formula of the project, one entry per law.

A detection law says how likely a sensor sweeping width ``W`` is to detect a target. Each law
appears in four places of the paper's search theory, all kept here (:data:`LAWS`):

- ``pod``: POD as a function of the coverage factor ``C`` (eq. 7-9), for parallel tracks at
  ``C = W / S`` -- for the inverse-cube law this is eq. 10, ``erf(sqrt(pi)/2 C)``;
- ``pod_slope``: ``d POD / d C``, and ``optimal_coverage``, the coverage at which a cell's
  marginal return equals a Lagrange multiplier (the optimal-effort bound,
  :mod:`poc_env.theory.bound`);
- ``reach``: the farthest distance from a step at which the step-wise form can detect anything;
- ``code``: the law's compiled branch in :mod:`poc_env._kernels.sensing`, the step-wise
  (segment) form the environment sweeps with (eq. 12-14 on sample points).

Laws:

``inverse_cube``
    Koopman's inverse-cube law. One straight segment gives a point the exponent ``F`` of
    :func:`poc_env.theory.search_theory.segment_exponent` and ``p = 1 - exp(-F)``; exponents
    of consecutive steps add, and parallel tracks at spacing ``S`` average to eq. 10,
    ``POD = erf(sqrt(pi)/2 W/S)`` (eq. 11 is ``erf``).
``exponential``
    Random search: the effort ``W L`` a step spends in a cell is spread over the cell,
    ``p = 1 - exp(-W L / A)``; as a function of coverage ``POD = 1 - exp(-C)``.
``definite_range``
    Cookie cutter: every point within ``W / 2`` of the step (foot on it) is detected;
    ``POD = min(C, 1)``.

Adding a law: one :class:`DetectionLaw` entry here, its compiled branch in
:mod:`poc_env._kernels.sensing` (``LAW_CODES`` and the branches of ``_point_pod`` and
``sweep``), and its tests (``tests/theory/test_detection.py``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.special import erf

from poc_env._kernels.sensing import DEFINITE_RANGE, EXPONENTIAL, INVERSE_CUBE, LAW_CODES
from poc_env.errors import ConfigError

_SQRT_PI_2 = np.sqrt(np.pi) / 2.0

Array = np.ndarray


@dataclass(frozen=True)
class DetectionLaw:
    """One detection law (see the module docstring for the meaning of each field).

    Attributes
    ----------
    name:
        The value of ``sensor.law``.
    code:
        The law's compiled branch in :mod:`poc_env._kernels.sensing`.
    pod:
        POD of a coverage factor ``C >= 0`` (parallel tracks: ``C = W / S``, eq. 9-10).
    pod_slope:
        ``d POD / d C`` of :attr:`pod`.
    optimal_coverage:
        The bound's KKT coverage from ``g = ln(density / lambda) >= 0`` (every searched cell
        has the same marginal return); ``None`` when ``pod`` is linear up to saturation, and the
        bound fills the densest cells first.
    reach:
        ``reach(W, cutoff, cell)``: farthest distance from a step at which the step-wise form
        detects anything.
    indicator:
        The step-wise POD is 0 or 1 (``segment_pod`` returns a boolean array).
    needs_cell:
        The step-wise form needs the cell size (effort spread over a cell).
    """

    name: str
    code: int
    pod: Callable[[Array], Array]
    pod_slope: Callable[[Array], Array]
    optimal_coverage: Callable[[Array], Array] | None
    reach: Callable[[float, float, float], float]
    indicator: bool = False
    needs_cell: bool = False


LAWS: dict[str, DetectionLaw] = {
    law.name: law
    for law in (
        DetectionLaw(
            name="inverse_cube",
            code=INVERSE_CUBE,
            pod=lambda c: erf(_SQRT_PI_2 * c),  # eq. 10
            pod_slope=lambda c: np.exp(-np.pi * c * c / 4.0),
            optimal_coverage=lambda g: np.sqrt(4.0 / np.pi * g),
            reach=lambda w, cutoff, cell: cutoff,
        ),
        DetectionLaw(
            name="exponential",
            code=EXPONENTIAL,
            pod=lambda c: -np.expm1(-c),  # random search
            pod_slope=lambda c: np.exp(-c),
            optimal_coverage=lambda g: g,
            reach=lambda w, cutoff, cell: min(cutoff, cell * np.sqrt(2.0)),
            needs_cell=True,
        ),
        DetectionLaw(
            name="definite_range",
            code=DEFINITE_RANGE,
            pod=lambda c: np.minimum(c, 1.0),
            pod_slope=lambda c: (c < 1.0).astype(float),
            optimal_coverage=None,
            reach=lambda w, cutoff, cell: min(cutoff, 0.5 * w),
            indicator=True,
        ),
    )
}

if set(LAWS) != set(LAW_CODES) or any(LAW_CODES[k] != v.code for k, v in LAWS.items()):
    raise ImportError(
        "poc_env.theory.detection.LAWS and poc_env._kernels.sensing.LAW_CODES disagree"
    )

#: The law names, in table order (``sensor.law`` accepts these).
LAW_NAMES = tuple(LAWS)


def detection_law(name: str) -> DetectionLaw:
    """The table entry of law ``name``; ConfigError naming the allowed laws otherwise."""
    law = LAWS.get(name) if isinstance(name, str) else None
    if law is None:
        raise ConfigError("law", name, "one of " + ", ".join(LAWS))
    return law
