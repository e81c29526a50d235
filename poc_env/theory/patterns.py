"""Search patterns of §2.2: variable-angle parallel search (eq. 5-6), the rectangle searches of
Figs. 2-3, sector search (Fig. 5), expanding square (Fig. 6) and spiral search (Fig. 7).

Every generator returns a :class:`Track`: the waypoints in flying order (metres), the track
spacing where the pattern has one, and a mask telling search legs from connecting legs.

Conventions (SI units: metres, radians)
---------------------------------------
* Parallel search, ``theta_rad``: the region is rotated counter-clockwise by ``theta`` (eq. 5),
  lines parallel to the Y axis are planned, and the waypoints are rotated back clockwise by
  ``theta`` (eq. 6). A Y-axis line therefore runs along ``(sin θ, cos θ)`` in the original
  frame: **θ is the compass bearing of the track lines** (clockwise from north = +y).
  ``θ = 0`` gives north-south lines, ``θ = π/2`` east-west lines.
* Rectangle searches take the rectangle Q of §3.1.6 (``rect_theta_rad`` = direction of the
  ``length`` side from the x axis, counter-clockwise). A direction at angle ``α`` from the x
  axis has bearing ``π/2 - α``, which is the ``theta`` handed to :func:`parallel_search`.
* Circle patterns (sector, expanding square, spiral) take ``rotation_rad`` as an angle from the
  x axis, counter-clockwise; they turn counter-clockwise.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from numbers import Integral
from typing import Any

import numpy as np
import shapely
from shapely.geometry import Polygon

from poc_env.errors import ConfigError, check_positive
from poc_env.geometry import (
    as_polygon,
    polyline_length,
    rectangle_polygon,
    rotate_ccw,
    rotate_cw,
)

__all__ = [
    "PATTERN_KINDS",
    "Track",
    "expanding_square",
    "horizontal_line_search",
    "parallel_line_search",
    "parallel_search",
    "pattern_track",
    "sector_search",
    "spiral_search",
]

#: Upper bound on parallel lines / square legs / sector passes, to turn a unit mistake
#: (spacing in km instead of m) into an error rather than an out-of-memory.
MAX_LINES = 100_000


@dataclass(frozen=True, eq=False)
class Track:
    """A flight track in flying order.

    Parameters
    ----------
    kind:
        Pattern name: ``"parallel"``, ``"parallel_line"``, ``"horizontal_line"``, ``"sector"``,
        ``"expanding_square"`` or ``"spiral"``.
    waypoints:
        (k, 2) float64 array of positions in metres, in flying order (stored read-only).
    spacing_m:
        Track spacing S where the pattern has one (parallel: line spacing; expanding square:
        leg spacing; sector: gap between adjacent pass ends on the perimeter), else ``None``.
    search_mask:
        Optional (k - 1,) bool array, ``True`` where the leg ``waypoints[i] -> waypoints[i+1]``
        is a search leg and ``False`` for a connecting leg (turn between lines, hop across a
        hole, return to the datum). ``None`` means every leg is a search leg.
    """

    kind: str
    waypoints: np.ndarray
    spacing_m: float | None
    search_mask: np.ndarray | None = field(default=None)

    def __post_init__(self) -> None:
        wp = np.array(self.waypoints, dtype=np.float64, copy=True)
        if wp.ndim != 2 or wp.shape[1] != 2 or len(wp) < 1:
            raise ValueError(f"Track.waypoints must have shape (k, 2), got {wp.shape}")
        wp.setflags(write=False)
        object.__setattr__(self, "waypoints", wp)
        if self.search_mask is not None:
            mask = np.array(self.search_mask, dtype=bool, copy=True)
            if mask.shape != (max(len(wp) - 1, 0),):
                raise ValueError(
                    f"Track.search_mask must have shape ({len(wp) - 1},), got {mask.shape}"
                )
            mask.setflags(write=False)
            object.__setattr__(self, "search_mask", mask)

    @property
    def length_m(self) -> float:
        """Polyline length through all waypoints (search legs and connecting legs), metres."""
        return polyline_length(self.waypoints)

    @property
    def search_length_m(self) -> float:
        """Length of the search legs only, metres."""
        return float(sum(np.hypot(*(b - a)) for a, b in self.search_legs()))

    def search_legs(self) -> list[np.ndarray]:
        """The search legs as a list of (2, 2) arrays ``[start, end]``."""
        wp = self.waypoints
        n = len(wp) - 1
        idx = range(n) if self.search_mask is None else np.flatnonzero(self.search_mask)
        return [wp[i : i + 2] for i in idx]


# --------------------------------------------------------------------------------------------
# argument checks
# --------------------------------------------------------------------------------------------


def _check_finite(field_name: str, value: Any) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ConfigError(field_name, value, "a finite number (radians)") from None
    if isinstance(value, bool) or not math.isfinite(x):
        raise ConfigError(field_name, value, "a finite number (radians)")
    return x


def _check_point(field_name: str, value: Any) -> np.ndarray:
    try:
        p = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(field_name, value, "an [x, y] pair of finite numbers (metres)") from None
    if p.shape != (2,) or not np.all(np.isfinite(p)):
        raise ConfigError(field_name, value, "an [x, y] pair of finite numbers (metres)")
    return p


def _check_count(field_name: str, value: Any, what: str) -> None:
    if value > MAX_LINES:
        raise ConfigError(field_name, what, f"at most {MAX_LINES} lines/legs/passes")


# --------------------------------------------------------------------------------------------
# variable-angle parallel search (§2.2, eq. 5-6)
# --------------------------------------------------------------------------------------------


def _merge_intervals(intervals: list[tuple[float, float]], eps: float) -> list[list[float]]:
    """Sort 1-D intervals and merge the ones that overlap or touch (within ``eps``)."""
    merged: list[list[float]] = []
    for lo, hi in sorted(intervals):
        if merged and lo <= merged[-1][1] + eps:
            merged[-1][1] = max(merged[-1][1], hi)
        else:
            merged.append([lo, hi])
    return merged


def _line_intervals(rotated: Polygon, xs: np.ndarray) -> list[tuple[float, list[list[float]]]]:
    """For each vertical line ``x = xs[i]``, the y-intervals where it lies in ``rotated``.

    Lines that only touch the polygon (a point) are dropped; several intervals per line occur
    for non-convex polygons and polygons with holes.
    """
    minx, miny, maxx, maxy = rotated.bounds
    scale = max(maxx - minx, maxy - miny, 1.0)
    eps = 1e-9 * scale
    pad = 0.01 * scale + 1.0
    lines = shapely.linestrings(
        np.stack(
            [
                np.column_stack([xs, np.full_like(xs, miny - pad)]),
                np.column_stack([xs, np.full_like(xs, maxy + pad)]),
            ],
            axis=1,
        )
    )
    shapely.prepare(rotated)
    cuts = shapely.intersection(lines, rotated)
    out: list[tuple[float, list[list[float]]]] = []
    for x, cut in zip(xs, cuts, strict=True):
        intervals = []
        for part in shapely.get_parts(cut):
            if part.geom_type != "LineString" or part.length <= eps:
                continue
            ys = shapely.get_coordinates(part)[:, 1]
            intervals.append((float(ys.min()), float(ys.max())))
        merged = _merge_intervals(intervals, eps)
        if merged:
            out.append((float(x), merged))
    return out


def _boustrophedon(
    lines: list[tuple[float, list[list[float]]]], reverse: bool, first_up: bool
) -> tuple[np.ndarray, np.ndarray]:
    """Waypoints (rotated frame) and search mask flying ``lines`` back and forth."""
    order = lines[::-1] if reverse else lines
    pts: list[tuple[float, float]] = []
    mask: list[bool] = []
    for j, (x, intervals) in enumerate(order):
        up = first_up == (j % 2 == 0)
        segs = intervals if up else [[hi, lo] for lo, hi in reversed(intervals)]
        for a, b in segs:
            if pts:
                mask.append(False)  # turn to the next line, or hop over a hole/notch
            pts.append((x, a))
            pts.append((x, b))
            mask.append(True)
    return np.asarray(pts, dtype=float), np.asarray(mask, dtype=bool)


def parallel_search(
    region: Polygon | np.ndarray | Sequence[Sequence[float]],
    spacing_m: float,
    theta_rad: float,
    *,
    start: Sequence[float] | None = None,
) -> Track:
    """Variable-angle parallel search of a polygonal region (§2.2, Fig. 4, eq. 5-6).

    Step 1 rotates the region counter-clockwise by ``theta`` (eq. 5, :func:`rotate_ccw`).
    Step 2 plans lines parallel to the Y axis: the first at ``S/2`` right of the rotated
    region's minimum x, then one every ``S`` while still inside, so that with ``S == W`` the
    W-wide swaths tile the strip ``[min x, min x + n S]``; each line is cut by the polygon and
    the pieces are flown boustrophedon (up one line, down the next; on one line the pieces are
    visited in the flying direction). Step 3 rotates the waypoints back clockwise by ``theta``
    (eq. 6, :func:`rotate_cw`). Rotations are about the origin, as in the paper.

    The lines run along ``(sin θ, cos θ)``: ``theta`` is the lines' compass bearing (clockwise
    from north = +y). A region narrower than ``S`` across the lines gets one line through the
    middle of its extent. The paper states the method for convex polygons; here non-convex
    polygons and polygons with holes work too (a line may give several pieces; connecting legs
    between pieces or lines may leave the region, the waypoints never do). When ``S == W`` a
    strip narrower than ``S/2`` beyond the last line can stay outside the swaths.

    Parameters
    ----------
    region:
        Shapely ``Polygon`` (holes allowed) or an (n, 2) vertex array, metres.
    spacing_m:
        Line spacing S (the paper's W when the sweep width is used), metres, > 0.
    theta_rad:
        Direction angle θ of eq. 5-6, radians (finite).
    start:
        Optional [x, y]. Of the four possible starting corners (first or last line, flying up or
        down) the one closest to ``start`` is used. Default: first line, flying up (+y of the
        rotated frame).

    Returns
    -------
    Track
        ``kind="parallel"``, ``spacing_m=S``; ``search_mask`` marks the line pieces.

    Raises
    ------
    GeometryError
        Degenerate or self-intersecting region.
    ConfigError
        Non-positive or non-finite ``spacing_m``, non-finite ``theta_rad``, bad ``start``, or
        more than :data:`MAX_LINES` lines.
    """
    poly = as_polygon(region, "region")
    s = check_positive("spacing_m", spacing_m)
    theta = _check_finite("theta_rad", theta_rad)
    start_xy = None if start is None else _check_point("start", start)

    # Step 1 (eq. 5): rotate the region counter-clockwise by theta.
    rotated = shapely.transform(poly, lambda c: rotate_ccw(c, theta))
    minx, _, maxx, _ = rotated.bounds
    extent = maxx - minx

    # Step 2: lines parallel to Y at S/2, 3S/2, ... from min x, while inside.
    if extent < s:
        xs = np.array([0.5 * (minx + maxx)])
    else:
        n = math.floor((extent - 0.5 * s) / s) + 1
        _check_count("spacing_m", n, f"{s!r} m over a {extent:.6g} m wide region")
        xs = minx + 0.5 * s + s * np.arange(n, dtype=float)
        xs = xs[xs < maxx]
    lines = _line_intervals(rotated, xs)
    if not lines:  # only possible through round-off on a sliver; fall back to the middle
        lines = _line_intervals(rotated, np.array([0.5 * (minx + maxx)]))

    best: tuple[np.ndarray, np.ndarray] | None = None
    best_d = math.inf
    for reverse in (False, True):
        for first_up in (True, False):
            pts, mask = _boustrophedon(lines, reverse, first_up)
            # Step 3 (eq. 6): rotate the waypoints back clockwise by theta.
            wp = rotate_cw(pts, theta)
            if start_xy is None:
                best = (wp, mask)
                break
            d = float(np.hypot(*(wp[0] - start_xy)))
            if d < best_d - 1e-12:
                best, best_d = (wp, mask), d
        if start_xy is None:
            break
    assert best is not None
    return Track("parallel", best[0], s, best[1])


def _long_side_bearing(length_m: float, width_m: float, rect_theta: float) -> float:
    """Compass bearing of the long side of Q(center, length, width, rect_theta)."""
    alpha = rect_theta if length_m >= width_m else rect_theta + 0.5 * math.pi
    return 0.5 * math.pi - alpha  # direction alpha from x  <=>  bearing pi/2 - alpha


def _rectangle_search(
    kind: str,
    center: Sequence[float],
    length_m: float,
    width_m: float,
    rect_theta_rad: float,
    spacing_m: float,
    start: Sequence[float] | None,
) -> Track:
    c = _check_point("center", center)
    length = check_positive("length_m", length_m)
    width = check_positive("width_m", width_m)
    rect_theta = _check_finite("rect_theta_rad", rect_theta_rad)
    check_positive("spacing_m", spacing_m)
    bearing = _long_side_bearing(length, width, rect_theta)
    if kind == "horizontal_line":
        bearing -= 0.5 * math.pi  # short side: perpendicular to the long side
    rect = rectangle_polygon((float(c[0]), float(c[1])), length, width, rect_theta)
    return replace(parallel_search(rect, spacing_m, bearing, start=start), kind=kind)


def parallel_line_search(
    center: Sequence[float],
    length_m: float,
    width_m: float,
    rect_theta_rad: float,
    spacing_m: float,
    *,
    start: Sequence[float] | None = None,
) -> Track:
    """Parallel line search of a rectangle: tracks along its long side (§2.2, Fig. 2).

    A thin wrapper of :func:`parallel_search` on the rectangle Q of §3.1.6
    (:func:`~poc_env.geometry.rectangle_polygon`), with θ = the bearing of the long side. The
    long side is ``length_m`` (direction ``rect_theta_rad`` from the x axis) unless
    ``width_m > length_m``.

    Raises
    ------
    ConfigError
        Non-positive ``length_m``/``width_m``/``spacing_m``, non-finite ``rect_theta_rad``, or a
        bad ``center``/``start``.
    """
    return _rectangle_search(
        "parallel_line", center, length_m, width_m, rect_theta_rad, spacing_m, start
    )


def horizontal_line_search(
    center: Sequence[float],
    length_m: float,
    width_m: float,
    rect_theta_rad: float,
    spacing_m: float,
    *,
    start: Sequence[float] | None = None,
) -> Track:
    """Horizontal line search of a rectangle: tracks along its short side (§2.2, Fig. 3).

    Same arguments as :func:`parallel_line_search`; θ = the bearing of the short side.
    """
    return _rectangle_search(
        "horizontal_line", center, length_m, width_m, rect_theta_rad, spacing_m, start
    )


# --------------------------------------------------------------------------------------------
# datum-circle patterns (§2.2, Figs. 5-7)
# --------------------------------------------------------------------------------------------


def _unit(angles: np.ndarray) -> np.ndarray:
    return np.stack([np.cos(angles), np.sin(angles)], axis=-1)


def sector_search(
    center: Sequence[float],
    radius_m: float,
    *,
    passes: int | None = None,
    spacing_m: float | None = None,
    rotation_rad: float = 0.0,
) -> Track:
    """Sector search of the datum circle: repeated passes through the datum (§2.2, Fig. 5).

    Pass ``k`` (``k = 0 .. n-1``) is a diameter at angle ``rotation + k π / n`` from the x axis,
    flown through ``center`` from one end on the circle to the other; the direction alternates
    (pass 0 along ``+u``, pass 1 along ``-u``, ...) so that consecutive passes are joined by a
    short straight leg (a chord) between neighbouring points of the circle. The 2n pass ends
    are evenly spaced on the circle, the arc between neighbours being ``π R / n``.

    Parameters
    ----------
    center:
        Datum [x, y], metres.
    radius_m:
        Radius R of the datum circle, metres, > 0.
    passes:
        Number n of diameters (integer >= 1). Give exactly one of ``passes`` and ``spacing_m``.
    spacing_m:
        Largest allowed arc gap between adjacent pass ends; then ``n = ceil(π R / spacing)``.
    rotation_rad:
        Direction of the first pass from the x axis, radians.

    Returns
    -------
    Track
        ``kind="sector"``, ``spacing_m = π R / n`` (the perimeter gap); starts and ends on the
        circle; waypoints ``2k, 2k+1`` are the ends of pass ``k``.
    """
    c = _check_point("center", center)
    r = check_positive("radius_m", radius_m)
    rot = _check_finite("rotation_rad", rotation_rad)
    if (passes is None) == (spacing_m is None):
        raise ConfigError(
            "passes", passes, "give exactly one of passes (an integer >= 1) and spacing_m"
        )
    if passes is not None:
        if isinstance(passes, bool) or not isinstance(passes, Integral) or passes < 1:
            raise ConfigError("passes", passes, "an integer >= 1")
        n = int(passes)
        _check_count("passes", n, f"{n} passes")
    else:
        s = check_positive("spacing_m", spacing_m)
        n = max(1, math.ceil(math.pi * r / s))
        _check_count("spacing_m", n, f"{s!r} m on a {r!r} m circle")
    k = np.arange(n)
    u = _unit(rot + k * math.pi / n)  # (n, 2)
    sign = np.where(k % 2 == 0, 1.0, -1.0)[:, None]
    starts = c - sign * r * u
    ends = c + sign * r * u
    wp = np.stack([starts, ends], axis=1).reshape(-1, 2)
    mask = np.zeros(2 * n - 1, dtype=bool)
    mask[::2] = True
    return Track("sector", wp, math.pi * r / n, mask)


def _square_legs(spacing: float, n_legs: int) -> np.ndarray:
    """Offsets (n_legs + 1, 2) of a unit-orientation expanding square from its datum."""
    i = np.arange(n_legs)
    lengths = spacing * np.ceil((i + 1) / 2.0)  # S, S, 2S, 2S, 3S, 3S, ...
    steps = lengths[:, None] * _unit(i * 0.5 * math.pi)  # +x, +y, -x, -y, ... (CCW turns)
    steps = np.rint(steps / spacing) * spacing  # exact multiples of S (no 1e-17 cos(pi/2))
    return np.vstack([np.zeros((1, 2)), np.cumsum(steps, axis=0)])


def expanding_square(
    center: Sequence[float],
    spacing_m: float,
    radius_m: float,
    *,
    second_rotated: bool = True,
    rotation_rad: float = 0.0,
) -> Track:
    """Expanding square search from the datum (§2.2, Fig. 6).

    Starts at the datum; legs of length S, S, 2S, 2S, 3S, 3S, ..., each turning 90°
    counter-clockwise, the first along ``rotation_rad`` from the x axis. Legs are added four at a
    time until the square's half side (distance from the datum to the nearest side of the
    square the track encloses) is >= ``radius_m``; that takes ``4 ceil(R / S)`` legs. With
    ``second_rotated=True`` a leg returns to the datum and the pattern is flown a second time
    rotated by 45° (the paper's secondary search, rotated 45° for the most information gain).

    Parameters
    ----------
    center:
        Datum [x, y], metres.
    spacing_m:
        Track spacing S, metres, > 0.
    radius_m:
        Radius R of the datum circle to cover, metres, > 0.
    second_rotated:
        Fly the 45°-rotated second square after the first.
    rotation_rad:
        Direction of the first leg from the x axis, radians.

    Returns
    -------
    Track
        ``kind="expanding_square"``, ``spacing_m=S``; the leg back to the datum is a connecting
        leg in ``search_mask``.
    """
    c = _check_point("center", center)
    s = check_positive("spacing_m", spacing_m)
    r = check_positive("radius_m", radius_m)
    rot = _check_finite("rotation_rad", rotation_rad)
    n_legs = 4 * math.ceil(r / s - 1e-12)
    _check_count("spacing_m", n_legs, f"{s!r} m for a {r!r} m radius")
    local = _square_legs(s, n_legs)
    first = rotate_ccw(local, rot) + c
    if not second_rotated:
        return Track("expanding_square", first, s, np.ones(n_legs, dtype=bool))
    second = rotate_ccw(local, rot + 0.25 * math.pi) + c
    wp = np.vstack([first, second])  # second[0] == datum: the leg first[-1] -> datum returns
    mask = np.ones(len(wp) - 1, dtype=bool)
    mask[n_legs] = False
    return Track("expanding_square", wp, s, mask)


def spiral_search(
    center: Sequence[float],
    radius_m: float,
    *,
    slopes_deg: Sequence[float] = (20, 15, 10, 5),
    points_per_turn: int = 72,
    rotation_rad: float = 0.0,
) -> Track:
    """Spiral search of the datum circle (§2.2, Fig. 7).

    The paper only says the spiral "uses a 20° slope, and when the spiral approaches 360°
    switches to a 15° slope; then 10° and 5°". Interpretation used here: a logarithmic spiral
    ``r(φ) = r_k exp(φ tan ψ_k)``, whose pitch (angle between the track and the circle through
    the current point) is the constant ``ψ_k``, flown outward counter-clockwise, one full turn
    (360°) at each slope ψ in ``slopes_deg`` in turn. The radius is continuous at slope changes
    and ``r0 = R / Π_k exp(2π tan ψ_k)`` so that the last turn ends exactly on the circle of
    radius R. The track starts at ``r0`` from the datum (about 0.36 % of R for the default
    slopes), in direction ``rotation_rad``.

    Parameters
    ----------
    center:
        Datum [x, y], metres.
    radius_m:
        Radius R of the datum circle, metres, > 0.
    slopes_deg:
        Pitch angles ψ in degrees, each in (0, 90), one turn each, in flying order.
    points_per_turn:
        Waypoints per 360° turn (integer >= 8).
    rotation_rad:
        Polar angle of the first waypoint, radians.

    Returns
    -------
    Track
        ``kind="spiral"``, ``spacing_m=None``; waypoint ``k * points_per_turn`` starts turn k.
    """
    c = _check_point("center", center)
    r = check_positive("radius_m", radius_m)
    rot = _check_finite("rotation_rad", rotation_rad)
    try:
        psi = np.asarray(slopes_deg, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ConfigError("slopes_deg", slopes_deg, "a list of angles in (0, 90) degrees") from None
    if psi.size == 0 or not np.all(np.isfinite(psi)) or np.any((psi <= 0) | (psi >= 90)):
        raise ConfigError("slopes_deg", slopes_deg, "a non-empty list of angles in (0, 90) degrees")
    if (
        isinstance(points_per_turn, bool)
        or not isinstance(points_per_turn, Integral)
        or not 8 <= points_per_turn <= MAX_LINES
    ):
        raise ConfigError("points_per_turn", points_per_turn, f"an integer in [8, {MAX_LINES}]")
    m = int(points_per_turn)
    tan_psi = np.tan(np.radians(psi))
    growth = 2.0 * math.pi * tan_psi  # log-radius gained over one turn at each slope
    # log r at the start of each turn, counted back from log R so the end is exactly R.
    log_r_start = math.log(r) - np.cumsum(growth[::-1])[::-1]
    dphi = np.linspace(0.0, 2.0 * math.pi, m + 1)[:-1]  # (m,) turn-local angles
    log_r = (log_r_start[:, None] + dphi[None, :] * tan_psi[:, None]).reshape(-1)
    phi = (2.0 * math.pi * np.arange(psi.size)[:, None] + dphi[None, :]).reshape(-1)
    log_r = np.append(log_r, math.log(r))
    phi = np.append(phi, 2.0 * math.pi * psi.size)
    radius = np.exp(log_r)
    radius[-1] = r
    wp = c + radius[:, None] * _unit(rot + phi)
    return Track("spiral", wp, None, None)


# --------------------------------------------------------------------------------------------
# dispatcher
# --------------------------------------------------------------------------------------------

_PATTERNS: dict[str, Callable[..., Track]] = {
    "parallel": parallel_search,
    "parallel_line": parallel_line_search,
    "horizontal_line": horizontal_line_search,
    "sector": sector_search,
    "expanding_square": expanding_square,
    "spiral": spiral_search,
}

#: Pattern names accepted by :func:`pattern_track`.
PATTERN_KINDS: tuple[str, ...] = tuple(_PATTERNS)


def pattern_track(kind: str, **kwargs: Any) -> Track:
    """Build the track of pattern ``kind`` from keyword arguments.

    ``kind`` is one of :data:`PATTERN_KINDS`; ``kwargs`` are the keyword arguments of the
    matching generator (e.g. ``pattern_track("sector", center=(0, 0), radius_m=500, passes=6)``).

    Raises
    ------
    ConfigError
        Unknown ``kind`` (the message lists the allowed kinds), unknown or missing arguments,
        or any error of the generator.
    """
    fn = _PATTERNS.get(kind) if isinstance(kind, str) else None
    if fn is None:
        raise ConfigError("kind", kind, "one of " + ", ".join(PATTERN_KINDS))
    sig = inspect.signature(fn)
    try:
        sig.bind(**kwargs)
    except TypeError as exc:
        raise ConfigError(
            f"{kind}.arguments", sorted(kwargs), f"the parameters {list(sig.parameters)} ({exc})"
        ) from None
    return fn(**kwargs)
