"""The spill-charged rule-aware bound (poc_env.theory.spill_bound, issue 24, i24-spill)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.special import erf, erfc

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.coverage_boxes import cut_lines
from poc_env.agents.planning.flight_rules import plan_speeds, reserve_s
from poc_env.agents.planning.greedy_rectangles import _lines
from poc_env.agents.planning.refine import route_fits
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.theory import spill_bound as sbm
from poc_env.theory.bound import env_limits, rule_bound
from poc_env.theory.probability_map import Grid
from poc_env.theory.search_theory import sweep_track
from poc_env.theory.spill_bound import band_edges, band_rates, spill_bound

KM = 1000.0
#: a blob 150 km from field A (20, -60) km; with 1.5 h of endurance the rule-aware round trip
#: reaches 146 km: the blob lies mostly beyond the reach, within the sensor's 20 km spill.
BLOB_KM = (20.0, 90.0)
SIGMA_KM = 6.0


def _centres(grid: Grid):
    ox, oy = grid.origin_m
    xs = ox + grid.cell_m * (np.arange(grid.nx) + 0.5)
    ys = oy + grid.cell_m * (np.arange(grid.ny) + 0.5)
    return np.meshgrid(xs, ys)


def _blob(grid: Grid, centre_km, sigma_km: float) -> np.ndarray:
    x, y = _centres(grid)
    p = np.exp(-((x - centre_km[0] * KM) ** 2 + (y - centre_km[1] * KM) ** 2)
               / (2 * (sigma_km * KM) ** 2))  # fmt: skip
    return p / p.sum()


def _flown(sc, grid: Grid, prior, path) -> float:
    """POS of ``path`` in the environment's sensor model: the compiled inverse-cube step over
    the sample points, cut-off included, in steps of ``v_max dt`` (the environment's longest)."""
    s = sc.sensor.samples_per_cell
    belief = np.ascontiguousarray(grid.refine(prior, s))
    w = sc.sensor.sweep_width_m
    step = sc.uav.max_speed_mps * sc.episode.dt_s
    cutoff = sc.sensor.cutoff_sweep_widths * w
    return sweep_track(belief, grid, s, path, w, sc.sensor.law, cutoff, step_m=step)


def _far_case():
    sc = load_scenario("paper_6_2", {"uav.endurance_h": 1.5}).with_uavs(1)
    grid = Grid.from_config(sc.map)
    return sc, grid, _blob(grid, BLOB_KM, SIGMA_KM)


def _fits(sc):
    speeds = plan_speeds(sc, "max")
    s = np.asarray(sc.takeoff_m[0], dtype=float)
    land = np.asarray(sc.landing_m[0], dtype=float)
    u = sc.uav

    def fits(q):
        return route_fits(np.vstack([s, q, land]), speeds, u.max_turn_rate_rad_s,
                          u.usable_endurance_s, reserve_s(sc))  # fmt: skip

    return fits


def _rule_time(sc, path) -> float:
    """The rule-aware bound's own time of ``path`` (take-off ... landing): every leg at
    ``v_max`` but the last, flown home at the cruise speed (eq. 18's return rule); turns free."""
    legs = np.hypot(*np.diff(np.asarray(path, dtype=float), axis=0).T)
    u = sc.uav
    return float(legs[:-1].sum() / u.max_speed_mps + legs[-1] / u.cruise_speed_mps)


def _skims(sc, rng, count: int):
    """Adversarial flights: out towards the blob, back and forth along an arc of radius R
    about the field (the reach boundary faces the blob), home; R the largest for which the
    flight keeps the rule the bound relaxes (back within the usable endurance, home at the
    cruise speed, turns free: :func:`_rule_time`), so the track skims the blob from the very
    edge of its reach."""
    s = np.asarray(sc.takeoff_m[0], dtype=float)
    to_blob = np.array(BLOB_KM) * KM - s
    head = np.arctan2(to_blob[1], to_blob[0])
    budget = sc.uav.usable_endurance_s
    out = []
    for _ in range(count):
        half = np.radians(rng.uniform(0.2, 8.0))
        passes = int(rng.integers(1, 12))
        angles = [head + (half if i % 2 else -half) for i in range(passes + 1)]

        def flight(r, angles=angles):
            arc = [s + r * np.array([np.cos(a), np.sin(a)]) for a in angles]
            return np.vstack([s, *arc, s])

        lo, hi = 0.0, float(np.hypot(*to_blob))
        for _ in range(50):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if _rule_time(sc, flight(mid)) <= budget else (lo, mid)
        out.append(flight(lo))
    return out


def _lawnmowers(sc, rng, count: int):
    """Rule-keeping lawnmowers over random boxes at the blob's near edge, cut to eq. 18."""
    s = np.asarray(sc.takeoff_m[0], dtype=float)
    land = np.asarray(sc.landing_m[0], dtype=float)
    w = sc.sensor.sweep_width_m
    fits = _fits(sc)
    out = []
    for _ in range(count):
        c = np.array(BLOB_KM) * KM + np.array([rng.normal(0, 6), rng.uniform(-30, -10)]) * KM
        half = rng.uniform(5, 25, 2) * KM
        box = _lines(c - half, c + half, rng.choice([0.5, 1.0, 2.0, 3.0]) * w, s)
        wps, _ = cut_lines(box, fits, w)
        if len(wps):
            out.append(np.vstack([s, wps, land]))
    return out


#: the configurations the far case is bounded with (the default and a wider charge).
CONFIGS = ((1.0, 1.0, True), (1.0, 0.75, True))


@pytest.fixture(scope="module")
def far():
    sc, grid, prior = _far_case()
    b = spill_bound(sc, prior, configs=CONFIGS)
    rng = np.random.default_rng(11)
    skims = _skims(sc, rng, 16)
    flights = skims + _lawnmowers(sc, rng, 8)
    plan = make_allocation_plan(sc, prior=prior)
    flights.append(np.vstack([sc.takeoff_m[0], plan["uavs"][0]["waypoints_m"], sc.landing_m[0]]))
    flown = [_flown(sc, grid, prior, f) for f in flights]
    return sc, grid, prior, b, flown, skims


def test_rule_keeping_flights_stay_below_the_spill_charged_bound(far):
    """A blob mostly beyond one UAV's round-trip reach, within the sensor's spill: flights that
    skim the reach boundary, lawnmowers at the blob's edge and the allocation planner's plan,
    each flown through the environment's own sensor model, stay below the spill-charged bound,
    which is well below the rule-aware bound (that credits the blob's first 20 km as if flown
    over)."""
    _, _, _, b, flown, _ = far
    assert max(flown) > 0.02  # the blob is found, mostly through the spill
    assert max(flown) <= b.upper
    assert b.upper < 0.75 * b.rule
    assert b.upper == min([b.rule, *b.by_config.values()])


def _track(path, step: float):
    """Points every ``step`` metres along ``path`` (the middle of each piece) and their lengths."""
    pts, lens = [], []
    for p, q in itertools.pairwise(path):
        n = max(1, int(np.ceil(np.hypot(*(q - p)) / step)))
        t = (np.arange(n) + 0.5) / n
        pts.append(p + t[:, None] * (q - p))
        lens.append(np.full(n, np.hypot(*(q - p)) / n))
    return np.vstack(pts), np.concatenate(lens)


def test_the_skims_far_exponent_fits_the_programs_far_budget(far):
    """The far part of the relaxation, checked on the skimming flights themselves against the
    program's own polymatroids (:func:`relaxation_blocks`): for each far block (band
    ``[r_k, r_{k+1})``) and threshold t, the exponent-area the track in the band gives the
    block's cells of transit ``>= t`` (each cell's exponent at its nearest sample point, as
    eq. 2), in coverage units, is at most the block's capacity ``rate (T_u - t)``; and every
    track point in a cell's band is at least that cell's transit away in rule time. Fails with
    ``h_k`` = 0, with a band's transit taken at its inner edge, or a mis-scaled kernel."""
    sc, grid, _, _, _, skims = far
    lim = env_limits(sc)
    w, v = lim.sweep_width_m, lim.speed_mps
    budget = sc.uav.usable_endurance_s
    s_ = sc.sensor.samples_per_cell
    hh = grid.cell_m / s_
    ox, oy = grid.origin_m
    off = (np.arange(s_) + 0.5) * hh
    field = np.asarray(lim.takeoff_m[0])
    far_blocks = [b for b in sbm.relaxation_blocks(sc, CONFIGS[1]) if b.band > 0]
    assert far_blocks and all(b.cells.size for b in far_blocks)
    checked = 0
    for path in skims[:5]:
        pts, lens = _track(path, 400.0)
        r_pt = np.hypot(*(pts - field).T)
        t_pt = r_pt / v + r_pt / sc.uav.cruise_speed_mps
        for blk in far_blocks:
            iy, ix = np.divmod(blk.cells, grid.nx)
            sx = ox + ix[:, None] * grid.cell_m + off[None, :]
            sy = oy + iy[:, None] * grid.cell_m + off[None, :]
            dx = np.abs(sx[None, :, :] - pts[:, None, None, 0]).min(axis=2)
            dy = np.abs(sy[None, :, :] - pts[:, None, None, 1]).min(axis=2)
            d = np.hypot(dx, dy)  # (points, cells): distance to each cell's nearest sample
            inband = (d >= blk.lo_m) & (d < blk.hi_m)
            assert np.all(t_pt[:, None] >= blk.transit_s[None, :] - 1e-6, where=inband)
            phi = np.where(inband, w**2 / (8 * np.pi * np.maximum(d, 1.0) ** 3), 0.0)
            per_cell = (phi * lens[:, None]).sum(axis=0)  # exponent: coverage units
            for t in np.unique(blk.transit_s[per_cell > 0]):
                got = per_cell[blk.transit_s >= t].sum()
                assert got <= blk.rate * (budget - t + 800.0 / v)  # two 400 m pieces
                checked += 1
    assert checked > 20


def test_every_cell_reachable_gives_the_rule_aware_bound_back():
    """paper_6_2 with two airfields: every cell is within each UAV's round trip, nothing is
    charged, and the program is the rule-aware relaxation up to its tangents (1e-4 above it,
    never below its value)."""
    sc = load_scenario("paper_6_2", {"map.cell_km": 10}).with_uavs(2)
    grid = Grid.from_config(sc.map)
    prior = (_blob(grid, (60.0, 80.0), 25.0) + _blob(grid, (150.0, 40.0), 15.0)) / 2
    b = spill_bound(sc, prior)
    rb = rule_bound(sc, prior)
    assert b.rule == rb.upper
    (prog,) = b.by_config.values()
    assert rb.pos - 1e-7 <= prog <= rb.upper + 1e-4
    assert b.upper == min(prog, rb.upper)


def test_pod_combination_inequality():
    """(1) and the hazard step of the module docstring: for coverage C and a uniform far
    exponent phi, ``1 - exp(-phi) (1 - E(C)) <= E(C + phi)`` (E = eq. 10), on a fine grid;
    equivalently the hazard ``E'(C) / (1 - E(C))`` is at least 1."""
    c = np.linspace(0.0, 6.0, 601)[:, None]
    phi = np.linspace(0.0, 4.0, 401)[None, :]

    def e(x):
        return erf(np.sqrt(np.pi) / 2 * x)

    assert np.all(1 - np.exp(-phi) * (1 - e(c)) <= e(c + phi) + 1e-12)
    h = np.exp(-np.pi * c**2 / 4) / erfc(np.sqrt(np.pi) / 2 * c)
    assert np.all(h >= 1 - 1e-12)


def test_band_rates_bound_the_lattice_sum():
    """Eq. (2): for random track points, the sum over the cells whose nearest sample point
    lies in band k of ``c^2 W^2 / (8 pi d^3)`` is at most ``h_k W`` (and the sampled sup is
    close to the largest value found: within 25 %)."""
    w, c, spc = 5000.0, 5000.0, 2
    edges = band_edges(5000.0, 24000.0)
    h = band_rates(edges, w, c, spc)
    rng = np.random.default_rng(3)
    span = 8
    offs = np.arange(-span, span + 1) * c
    sp = (np.arange(spc) + 0.5) * c / spc
    pts = (offs[:, None] + sp[None, :]).ravel()
    seen = np.zeros(len(h))
    for _ in range(400):
        sx, sy = rng.uniform(0, c, 2)
        dx = np.abs(pts - sx).reshape(offs.size, spc).min(axis=1)
        dy = np.abs(pts - sy).reshape(offs.size, spc).min(axis=1)
        d = np.hypot(dx[None, :], dy[:, None]).ravel()
        for k in range(len(h)):
            sel = (d >= edges[k]) & (d < edges[k + 1])
            seen[k] = max(seen[k], np.sum(c * c * w * w / (8 * np.pi * d[sel] ** 3)) / w)
    assert np.all(seen <= h)
    assert np.all(seen >= 0.75 * h)


def test_spill_bound_checks_its_input():
    sc, _, prior = _far_case()
    with pytest.raises(ConfigError, match="prior"):
        spill_bound(sc, prior[:-1])
    with pytest.raises(ConfigError, match="configs"):
        spill_bound(sc, prior, configs=((0.0, 1.0, True),))
    with pytest.raises(ConfigError, match="configs"):
        spill_bound(sc, prior, configs=((1.0, 1.5, True),))


def test_a_prior_without_mass_has_a_zero_bound():
    """No mass: the bound is 0 (the rule-aware one), not a solver error on an empty program."""
    sc, _, prior = _far_case()
    b = spill_bound(sc, np.zeros_like(prior))
    assert b.upper == 0.0 and b.rule == 0.0


def test_plan_prints_and_writes_the_spill_charged_bound(tmp_path, capsys):
    """``poc-env plan --spill-bound``: plan.json holds ``bound_spill`` (at most the rule-aware
    bound, the least of the two) and the table prints it; without the flag neither."""
    import json

    from poc_env.cli import main

    out = tmp_path / "plan.json"
    args = ["plan", "--scenario", "small", "--planner", "allocation", "--quiet", "--out"]
    assert main([*args, str(out), "--spill-bound"]) == 0
    plan = json.loads(out.read_text())
    assert 0 < plan["bound_spill"] <= plan["bound_rule"]
    assert "spill-charged bound" in capsys.readouterr().out
    assert main([*args, str(out)]) == 0
    assert "bound_spill" not in json.loads(out.read_text())
    assert "spill-charged bound" not in capsys.readouterr().out


@pytest.mark.parametrize("seed", [None, 1])
def test_the_fleets_allocation_plan_stays_below_with_short_endurance(seed):
    """paper_6_2's six UAVs from two airfields with 1.2 h of endurance: each airfield's group
    reaches part of the map only through the spill, so the charge tightens the bound (by over
    3 %), and the allocation planner's plan, every UAV's route swept in turn by the
    environment's sensor model (4 km steps), stays below it (the scenario's prior and a random
    one)."""
    from poc_env.agents.experiments.evaluate import episode_prior
    from poc_env.theory.probability_map import build_prior

    sc = load_scenario("paper_6_2", {"uav.endurance_h": 1.2})
    grid = Grid.from_config(sc.map)
    prior = build_prior(sc.map, None) if seed is None else episode_prior(sc, seed)
    b = spill_bound(sc, prior)
    assert b.upper < 0.97 * b.rule
    plan = make_allocation_plan(sc, prior=prior)
    s = sc.sensor.samples_per_cell
    belief = np.ascontiguousarray(grid.refine(prior, s))
    w = sc.sensor.sweep_width_m
    flown = 0.0
    for k, u in enumerate(plan["uavs"]):
        path = np.vstack([sc.takeoff_m[k], u["waypoints_m"], sc.landing_m[k]])
        flown += sweep_track(belief, grid, s, path, w, sc.sensor.law,
                             sc.sensor.cutoff_sweep_widths * w,
                             step_m=sc.uav.max_speed_mps * sc.episode.dt_s)  # fmt: skip
    assert 0.1 < flown <= b.upper
