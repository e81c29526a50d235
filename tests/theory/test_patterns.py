"""Tests of the §2.2 search patterns (poc_env.theory.patterns) and their gallery figure."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from shapely.geometry import LineString, Point, Polygon
from shapely.ops import unary_union

from poc_env.errors import ConfigError, GeometryError
from poc_env.geometry import covers_points, rectangle_polygon, rotate_ccw, rotate_cw
from poc_env.theory.patterns import (
    PATTERN_KINDS,
    Track,
    expanding_square,
    horizontal_line_search,
    parallel_line_search,
    parallel_search,
    pattern_track,
    sector_search,
    spiral_search,
)

# ------------------------------------------------------------------ regions (metres)
CONVEX = Polygon([(0, 0), (9000, 1000), (10000, 6000), (4000, 8000), (-1000, 4000)])
L_SHAPE = Polygon([(0, 0), (8000, 0), (8000, 3000), (3000, 3000), (3000, 8000), (0, 8000)])
U_SHAPE = Polygon(
    [
        (0, 0),
        (9000, 0),
        (9000, 8000),
        (6000, 8000),
        (6000, 3000),
        (3000, 3000),
        (3000, 8000),
        (0, 8000),
    ],
)
HOLED = Polygon(
    [(0, 0), (10000, 0), (10000, 8000), (0, 8000)],
    [[(3000, 2000), (7000, 2000), (7000, 5000), (3000, 5000)]],
)
REGIONS = {"convex": CONVEX, "L": L_SHAPE, "U": U_SHAPE, "holed": HOLED}
ANGLES_DEG = (0.0, 37.0, 90.0, 130.0)

region_ids = pytest.mark.parametrize("name", list(REGIONS))
angle_ids = pytest.mark.parametrize("angle_deg", ANGLES_DEG)


def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """z component of the 2-D cross product."""
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def _line_xs(track: Track, theta: float, spacing: float) -> np.ndarray:
    """Distinct x of the lines in the rotated frame of eq. 5 (sorted)."""
    x = np.sort(rotate_ccw(track.waypoints, theta)[:, 0])
    groups = np.split(x, np.flatnonzero(np.diff(x) > 1e-6 * spacing) + 1)
    return np.array([g.mean() for g in groups])


# ------------------------------------------------------------------ rotation (eq. 5-6)
def test_rotation_round_trip_and_direction() -> None:
    rng = np.random.default_rng(0)
    p = rng.uniform(-1e4, 1e4, size=(50, 2))
    for t in (0.0, 0.3, -2.0, math.radians(130), 7.5):
        np.testing.assert_allclose(rotate_cw(rotate_ccw(p, t), t), p, atol=1e-9, rtol=0)
    # eq. 5 is counter-clockwise: +x rotated by 90 degrees becomes +y.
    np.testing.assert_allclose(rotate_ccw([[1.0, 0.0]], math.pi / 2), [[0.0, 1.0]], atol=1e-15)


# ------------------------------------------------------------------ parallel search
@region_ids
@angle_ids
def test_parallel_waypoints_inside_region(name: str, angle_deg: float) -> None:
    region = REGIONS[name]
    track = parallel_search(region, 500.0, math.radians(angle_deg))
    assert track.kind == "parallel"
    assert track.waypoints.dtype == np.float64 and track.waypoints.shape[1] == 2
    assert len(track.waypoints) >= 4
    assert covers_points(region, track.waypoints, tol=1e-6).all()
    # every search leg is inside the region (not just its ends)
    for leg in track.search_legs():
        assert region.buffer(1e-6).covers(LineString(leg))


@region_ids
@angle_ids
def test_parallel_spacing_exact(name: str, angle_deg: float) -> None:
    region, s = REGIONS[name], 700.0
    theta = math.radians(angle_deg)
    track = parallel_search(region, s, theta)
    xs = _line_xs(track, theta, s)
    rotated = shapely.transform(region, lambda c: rotate_ccw(c, theta))
    minx, _, maxx, _ = rotated.bounds
    assert xs[0] == pytest.approx(minx + s / 2, rel=1e-9, abs=1e-6)
    np.testing.assert_allclose(np.diff(xs), s, rtol=1e-6)
    # every line that fits is flown: the next one would be outside
    assert xs[-1] < maxx <= xs[-1] + s
    # every search leg is parallel to the rotated Y axis, i.e. bearing theta
    for a, b in track.search_legs():
        d = (b - a) / np.hypot(*(b - a))
        assert abs(abs(d @ np.array([math.sin(theta), math.cos(theta)])) - 1) < 1e-9


@pytest.mark.parametrize(("name", "angle_deg"), [("L", 135.0), ("U", 90.0), ("holed", 0.0)])
def test_parallel_nonconvex_lines_split_and_boustrophedon(name: str, angle_deg: float) -> None:
    region, s, theta = REGIONS[name], 1000.0, math.radians(angle_deg)
    track = parallel_search(region, s, theta)
    assert track.search_mask is not None
    wp = rotate_ccw(track.waypoints, theta)  # frame of eq. 5: lines along the Y axis
    legs = [wp[i : i + 2] for i in np.flatnonzero(track.search_mask)]
    key = [round(a[0] / s * 2) for a, _ in legs]  # line index (odd multiples of S/2 + offset)
    # some line is cut into two pieces by the notch / hole
    assert max(key.count(k) for k in set(key)) == 2
    # flying direction alternates from line to line, and pieces of one line share it
    directions: dict[int, set[float]] = {}
    for k, (a, b) in zip(key, legs, strict=True):
        directions.setdefault(k, set()).add(float(np.sign(b[1] - a[1])))
    assert all(len(d) == 1 for d in directions.values())
    sign = {k: next(iter(d)) for k, d in directions.items()}
    ordered = [sign[k] for k in sorted(sign)]
    assert all(ordered[i] == -ordered[i + 1] for i in range(len(ordered) - 1))
    # the hop between pieces of one line keeps the flying direction (no back-tracking)
    hops = 0
    for i in np.flatnonzero(~track.search_mask):
        if abs(wp[i + 1, 0] - wp[i, 0]) < 1e-6:
            hops += 1
            assert np.sign(wp[i + 1, 1] - wp[i, 1]) == sign[round(wp[i, 0] / s * 2)]
    assert hops >= 1


def _swath_fraction(region: Polygon, track: Track, w: float, cap_style: str) -> float:
    """Fraction of ``region`` inside the search legs buffered by W/2."""
    legs = track.search_legs()
    assert legs
    swath = unary_union([LineString(leg).buffer(w / 2, cap_style=cap_style) for leg in legs])
    return region.intersection(swath).area / region.area


@pytest.mark.parametrize("ratio", [0.6, 1.0])
@region_ids
@angle_ids
def test_parallel_coverage(name: str, angle_deg: float, ratio: float) -> None:
    """Search legs buffered by W/2 with ROUND caps cover >= 99 % of the region for S <= W."""
    region, w = REGIONS[name], 250.0
    track = parallel_search(region, ratio * w, math.radians(angle_deg))
    covered = _swath_fraction(region, track, w, "round")
    assert covered >= 0.99, covered


def test_parallel_coverage_drops_when_spacing_exceeds_width() -> None:
    """Sanity check of the coverage measure itself: S = 2W covers about half the region."""
    w = 250.0
    track = parallel_search(L_SHAPE, 2 * w, 0.3)
    assert 0.45 < _swath_fraction(L_SHAPE, track, w, "flat") < 0.56


def test_parallel_track_length_hand_computed() -> None:
    # 4 km (x) by 10 km (y), S = 1 km, theta = 0: lines at x = 0.5, 1.5, 2.5, 3.5 km,
    # 4 lines of 10 km plus 3 connecting legs of 1 km = 43 km.
    rect = [(0, 0), (4000, 0), (4000, 10000), (0, 10000)]
    track = parallel_search(rect, 1000.0, 0.0)
    assert track.length_m == pytest.approx(43000.0, rel=1e-12)
    assert track.search_length_m == pytest.approx(40000.0, rel=1e-12)
    assert track.spacing_m == 1000.0
    np.testing.assert_allclose(track.waypoints[:3], [[500, 0], [500, 10000], [1500, 10000]])
    # 10 km (x) by 4 km (y) at theta = 90 deg: lines run east-west, again 4 x 10 km + 3 x 1 km.
    wide = [(0, 0), (10000, 0), (10000, 4000), (0, 4000)]
    track = parallel_search(wide, 1000.0, math.pi / 2)
    assert track.length_m == pytest.approx(43000.0, rel=1e-9)
    ys = np.unique(np.round(track.waypoints[:, 1], 6))
    np.testing.assert_allclose(ys, [500, 1500, 2500, 3500])


def test_parallel_theta_is_compass_bearing() -> None:
    square = [(-5000, -5000), (5000, -5000), (5000, 5000), (-5000, 5000)]
    for deg in (0.0, 30.0, 90.0, 150.0):
        t = math.radians(deg)
        a, b = parallel_search(square, 1000.0, t).search_legs()[0]
        d = (b - a) / np.hypot(*(b - a))
        assert abs(d @ np.array([math.sin(t), math.cos(t)])) == pytest.approx(1.0, abs=1e-12)


def test_parallel_narrow_region_single_middle_line() -> None:
    sliver = [(0, 0), (300, 0), (300, 5000), (0, 5000)]
    track = parallel_search(sliver, 1000.0, 0.0)
    np.testing.assert_allclose(track.waypoints, [[150, 0], [150, 5000]])


def test_parallel_start_picks_nearest_corner() -> None:
    rect = [(0, 0), (4000, 0), (4000, 10000), (0, 10000)]
    corners = {(-500, -500): (500, 0), (-500, 11000): (500, 10000)}
    corners |= {(5000, -500): (3500, 0), (5000, 11000): (3500, 10000)}
    base = parallel_search(rect, 1000.0, 0.0)
    for start, first in corners.items():
        track = parallel_search(rect, 1000.0, 0.0, start=start)
        np.testing.assert_allclose(track.waypoints[0], first)
        assert track.length_m == pytest.approx(base.length_m)
        assert len(track.search_legs()) == 4


# ------------------------------------------------------------------ rectangle searches
@pytest.mark.parametrize("rect_deg", [0.0, 25.0, 90.0, 160.0])
def test_parallel_line_vs_horizontal_line(rect_deg: float) -> None:
    center, length, width, s = (1000.0, -2000.0), 10000.0, 4000.0, 500.0
    rt = math.radians(rect_deg)
    rect = rectangle_polygon(center, length, width, rt)
    long_dir = np.array([math.cos(rt), math.sin(rt)])
    short_dir = np.array([-math.sin(rt), math.cos(rt)])
    for fn, kind, along, n_lines, leg in (
        (parallel_line_search, "parallel_line", long_dir, 8, length),
        (horizontal_line_search, "horizontal_line", short_dir, 20, width),
    ):
        track = fn(center, length, width, rt, s)
        assert track.kind == kind
        assert covers_points(rect, track.waypoints, tol=1e-6).all()
        legs = track.search_legs()
        assert len(legs) == n_lines
        a, b = max(legs, key=lambda ab: np.hypot(*(ab[1] - ab[0])))
        assert np.hypot(*(b - a)) == pytest.approx(leg, rel=1e-9)
        d = (b - a) / np.hypot(*(b - a))
        assert abs(d @ along) == pytest.approx(1.0, abs=1e-9)


def test_rectangle_search_long_side_is_width_when_wider() -> None:
    # width > length: the long side is the width direction (perpendicular to rect_theta).
    track = parallel_line_search((0, 0), 2000.0, 6000.0, 0.0, 500.0)
    a, b = track.search_legs()[0]
    assert abs(b[0] - a[0]) < 1e-9 and abs(b[1] - a[1]) == pytest.approx(6000.0)


# ------------------------------------------------------------------ sector search
@pytest.mark.parametrize(("radius", "spacing"), [(1000.0, 300.0), (2500.0, 1000.0)])
def test_sector_passes_through_datum(radius: float, spacing: float) -> None:
    center = np.array([300.0, -700.0])
    track = sector_search(center, radius, spacing_m=spacing, rotation_rad=0.4)
    n = math.ceil(math.pi * radius / spacing)
    assert len(track.waypoints) == 2 * n
    legs = track.search_legs()
    assert len(legs) == n
    for leg in legs:
        assert LineString(leg).distance(Point(center)) < 1e-9
        assert np.hypot(*(leg[1] - leg[0])) == pytest.approx(2 * radius)
    dist = np.hypot(*(track.waypoints - center).T)
    assert np.all(dist <= radius + 1e-6)
    np.testing.assert_allclose(dist, radius)  # starts and ends (and turns) on the circle
    # the perimeter gap between adjacent pass ends is pi R / n <= spacing
    assert track.spacing_m == pytest.approx(math.pi * radius / n)
    assert track.spacing_m <= spacing
    ang = np.sort(np.mod(np.arctan2(*(track.waypoints - center).T[::-1]), 2 * math.pi))
    gaps = np.diff(np.append(ang, ang[0] + 2 * math.pi))
    np.testing.assert_allclose(gaps * radius, track.spacing_m, rtol=1e-9)
    # passes alternate: each pass starts next to where the previous one ended
    wp = track.waypoints
    joins = np.hypot(*(wp[2::2] - wp[1:-1:2]).T)
    np.testing.assert_allclose(joins, 2 * radius * math.sin(math.pi / (2 * n)))


def test_sector_passes_argument() -> None:
    track = pattern_track("sector", center=(0, 0), radius_m=100.0, passes=3)
    np.testing.assert_allclose(track.waypoints[:2], [[-100, 0], [100, 0]], atol=1e-12)
    assert len(track.waypoints) == 6


# ------------------------------------------------------------------ expanding square
@pytest.mark.parametrize(("spacing", "radius"), [(100.0, 450.0), (250.0, 1000.0), (1.0, 0.3)])
def test_expanding_square(spacing: float, radius: float) -> None:
    center = np.array([50.0, 20.0])
    track = expanding_square(center, spacing, radius, rotation_rad=0.2)
    wp = track.waypoints
    datum_idx = np.flatnonzero(np.hypot(*(wp - center).T) < 1e-9)
    assert datum_idx[0] == 0 and len(datum_idx) == 2
    m = int(datum_idx[1]) - 1  # legs of the first square
    first, second = wp[: m + 1], wp[m + 1 :]
    assert len(second) == m + 1
    expected = spacing * np.ceil(np.arange(1, m + 1) / 2)
    for part in (first, second):
        np.testing.assert_allclose(np.hypot(*np.diff(part, axis=0).T), expected, rtol=1e-9)
        d = np.diff(part, axis=0)
        turns = _cross(d[:-1], d[1:]) / (np.hypot(*d[:-1].T) * np.hypot(*d[1:].T))
        np.testing.assert_allclose(turns, 1.0)  # +90 degrees (CCW) at every corner
    # second pattern's first leg at 45 degrees to the first pattern's first leg
    u, v = first[1] - first[0], second[1] - second[0]
    ang = math.degrees(math.atan2(_cross(u, v), u @ v))
    assert ang == pytest.approx(45.0)
    # final half side >= radius, and one ring fewer would not reach it
    for part, rot in ((first, 0.2), (second, 0.2 + math.pi / 4)):
        loc = rotate_ccw(part - center, -rot)
        half = min(loc[:, 0].max(), -loc[:, 0].min(), loc[:, 1].max(), -loc[:, 1].min())
        assert half >= radius - 1e-9
        assert half - spacing < radius
    assert track.search_mask is not None and not track.search_mask[m]
    assert track.search_mask.sum() == 2 * m
    single = expanding_square(center, spacing, radius, second_rotated=False)
    assert len(single.waypoints) == m + 1


# ------------------------------------------------------------------ spiral
@pytest.mark.parametrize("radius", [500.0, 8000.0])
def test_spiral_pitch_and_end_radius(radius: float) -> None:
    center = np.array([-100.0, 40.0])
    ppt = 72
    track = spiral_search(center, radius, points_per_turn=ppt)
    rel = track.waypoints - center
    r = np.hypot(*rel.T)
    phi = np.unwrap(np.arctan2(rel[:, 1], rel[:, 0]))
    assert len(r) == 4 * ppt + 1
    assert r[-1] == pytest.approx(radius, rel=1e-12)
    assert np.all(np.diff(r) > 0) and np.all(np.diff(phi) > 0)  # outward, counter-clockwise
    assert phi[-1] - phi[0] == pytest.approx(4 * 2 * math.pi)
    for k, slope in enumerate((20, 15, 10, 5)):
        seg = slice(k * ppt, (k + 1) * ppt + 1)
        rr, pp = r[seg], phi[seg]
        turn_pitch = math.degrees(math.atan(math.log(rr[-1] / rr[0]) / (pp[-1] - pp[0])))
        assert turn_pitch == pytest.approx(slope, abs=0.5)
        local = np.degrees(np.arctan(np.diff(np.log(rr)) / np.diff(pp)))
        np.testing.assert_allclose(local, slope, atol=0.5)
    # radius continuous at slope changes: no jump bigger than the neighbouring steps
    steps = np.diff(r)
    assert np.all(steps[1:] / steps[:-1] < 1.2)
    assert track.spacing_m is None
    r0 = radius / math.prod(
        math.exp(2 * math.pi * math.tan(math.radians(a))) for a in (20, 15, 10, 5)
    )
    assert r[0] == pytest.approx(r0, rel=1e-9)


# ------------------------------------------------------------------ dispatcher
def test_pattern_track_dispatches_every_kind() -> None:
    kwargs = {
        "parallel": {"region": CONVEX, "spacing_m": 500.0, "theta_rad": 0.2},
        "parallel_line": {
            "center": (0, 0),
            "length_m": 4000.0,
            "width_m": 2000.0,
            "rect_theta_rad": 0.1,
            "spacing_m": 500.0,
        },
        "sector": {"center": (0, 0), "radius_m": 1000.0, "spacing_m": 400.0},
        "expanding_square": {"center": (0, 0), "spacing_m": 200.0, "radius_m": 900.0},
        "spiral": {"center": (0, 0), "radius_m": 1000.0},
    }
    kwargs["horizontal_line"] = kwargs["parallel_line"]
    assert set(kwargs) == set(PATTERN_KINDS)
    for kind, kw in kwargs.items():
        track = pattern_track(kind, **kw)
        assert track.kind == kind and track.length_m > 0


def test_pattern_track_unknown_kind() -> None:
    with pytest.raises(ConfigError, match=r"kind.*parallel.*spiral"):
        pattern_track("zigzag", center=(0, 0))
    with pytest.raises(ConfigError, match=r"sector\.arguments"):
        pattern_track("sector", center=(0, 0), radius=10.0)


# ------------------------------------------------------------------ bad input
SQUARE = [(0, 0), (1000, 0), (1000, 1000), (0, 1000)]


@pytest.mark.parametrize("bad", [0.0, -5.0, float("nan"), float("inf"), "x"])
def test_bad_numbers_raise_config_error(bad: object) -> None:
    cases = [
        ("spacing_m", lambda: parallel_search(SQUARE, bad, 0.0)),
        ("spacing_m", lambda: parallel_line_search((0, 0), 10, 5, 0, bad)),
        ("length_m", lambda: parallel_line_search((0, 0), bad, 5, 0, 1)),
        ("width_m", lambda: horizontal_line_search((0, 0), 10, bad, 0, 1)),
        ("radius_m", lambda: sector_search((0, 0), bad, passes=3)),
        ("spacing_m", lambda: sector_search((0, 0), 10, spacing_m=bad)),
        ("spacing_m", lambda: expanding_square((0, 0), bad, 10)),
        ("radius_m", lambda: expanding_square((0, 0), 1, bad)),
        ("radius_m", lambda: spiral_search((0, 0), bad)),
    ]
    for name, call in cases:
        with pytest.raises(ConfigError, match=name):
            call()


@pytest.mark.parametrize("bad", [float("nan"), float("inf"), None])
def test_non_finite_angles_raise(bad: object) -> None:
    with pytest.raises(ConfigError, match="theta_rad"):
        parallel_search(SQUARE, 100.0, bad)
    with pytest.raises(ConfigError, match="rect_theta_rad"):
        parallel_line_search((0, 0), 10, 5, bad, 1)
    with pytest.raises(ConfigError, match="rotation_rad"):
        sector_search((0, 0), 10, passes=2, rotation_rad=bad)


def test_other_bad_arguments() -> None:
    with pytest.raises(ConfigError, match="passes"):
        sector_search((0, 0), 10)  # neither passes nor spacing_m
    with pytest.raises(ConfigError, match="passes"):
        sector_search((0, 0), 10, passes=3, spacing_m=2.0)  # both
    for bad in (0, 2.5, True):
        with pytest.raises(ConfigError, match="passes"):
            sector_search((0, 0), 10, passes=bad)
    for slopes in ((), (20, 90), (0, 10), (20, float("nan"))):
        with pytest.raises(ConfigError, match="slopes_deg"):
            spiral_search((0, 0), 10, slopes_deg=slopes)
    with pytest.raises(ConfigError, match="points_per_turn"):
        spiral_search((0, 0), 10, points_per_turn=3)
    with pytest.raises(ConfigError, match="center"):
        sector_search((0, float("nan")), 10, passes=2)
    with pytest.raises(ConfigError, match="start"):
        parallel_search(SQUARE, 100.0, 0.0, start=(1, 2, 3))
    with pytest.raises(ConfigError, match="spacing_m"):
        parallel_search(SQUARE, 1e-3, 0.0)  # 1e6 lines: a unit mistake, not a plan


@pytest.mark.parametrize(
    "region",
    [
        [(0, 0), (1, 1), (2, 2)],  # zero area
        [(0, 0), (1, 1), (1, 0), (0, 1)],  # bow tie (self-intersecting)
        [(0, 0), (1, 0)],  # too few vertices
        Polygon([(0, 0), (2, 2), (2, 0), (0, 2)]),  # invalid shapely polygon
    ],
)
def test_bad_polygons_raise_geometry_error(region: object) -> None:
    with pytest.raises(GeometryError, match="region"):
        parallel_search(region, 0.1, 0.0)


# ------------------------------------------------------------------ gallery figure
def test_pattern_gallery_writes_pngs(tmp_path) -> None:
    from poc_env.viz.figures import pattern_gallery

    paths = pattern_gallery(tmp_path / "gallery")
    assert len(paths) == len(PATTERN_KINDS)
    for kind in PATTERN_KINDS:
        assert any(kind in p.stem for p in paths)
    for p in paths:
        data = p.read_bytes()
        assert p.suffix == ".png" and len(data) > 1000
        assert data[:8] == b"\x89PNG\r\n\x1a\n"
        assert data[12:16] == b"IHDR"
