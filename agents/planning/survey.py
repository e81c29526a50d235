"""Region surveys: given regions with their pattern, spacing and direction, score the plan.

This is the §6.1 workflow (Tables 4 and 5): each UAV gets a region (a polygon searched by the
variable-angle parallel search, or a search-base circle searched by a sector, expanding-square
or spiral pattern), its track is generated, and the report gives per UAV the track length,
POD, POC, POS, the flight time and feasibility (eq. 17-18), the swarm's POSC, and the physical
optimum for the same total effort (:mod:`poc_env.theory.bound`).

POD is eq. 10 with the region's spacing for parallel search (as in the paper's Table 4). For the
circle patterns, which have no single spacing, POD is the law's POD of the coverage factor
C = W L / A (eq. 7-8) of the track over the circle. POC_i is the area-weighted POC of the
region with the overlap rule of §3.1.6 (a cell already allocated to an earlier UAV counts 0).
The ``bound`` is the optimal allocation of the same effort under the scenario's law (no plan
scored by eq. 10 can beat it); the ``ceiling`` is the optimum under the definite-range law,
``POD = min(C, 1)``, which no sensor of sweep width W can beat in any cell -- the step-wise
inverse-cube law can exceed the erf allocation by a hair at low coverage (erf(sqrt(pi)/2 C) =
C - pi C^3 / 12 + ...), never the ceiling.
The ``pos_flown`` column is what the step-wise detection law actually finds when the tracks are
flown over the belief, UAV after UAV (eq. 14) -- the environment's number, not a formula.
"""

from __future__ import annotations

import csv
import io
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import poc_env.limits as limits
from poc_env.config import (
    CONFIG_DIR,
    DEG,
    KM,
    Scenario,
    _choice,
    _coerce,
    _f,
    _from_mapping,
    _vec2,
    _yaml_key,
    load_scenario,
    read_yaml,
)
from poc_env.errors import ConfigError
from poc_env.io import write_text_atomic
from poc_env.theory.bound import physical_optimum
from poc_env.theory.probability_map import Grid, build_prior
from poc_env.theory.search_theory import (
    parallel_coverage,
    pod_from_coverage,
    swarm_pos,
    sweep_track,
)
from poc_env.theory.timing import flight_time_s, is_feasible

PATTERNS = ("parallel", "sector", "expanding_square", "spiral")
#: Most lines (region extent / spacing) a region's pattern may fly: 10^4 lines of a 200 km
#: region are 2 million km of track, far beyond any endurance.
MAX_LINES = 10_000


@dataclass(frozen=True)
class RegionSpec:
    """One UAV's region and search pattern in a region plan (YAML keys with units).

    Every field is checked by the scenario's validation layer (:func:`poc_env.config._coerce`):
    ``id`` an integer, ``spacing_km`` and ``radius_km`` in (0, 2000], ``second_search`` true or
    false; a pattern may fly at most :data:`MAX_LINES` lines (its extent over its spacing).
    Geometry errors name the region's id.
    """

    id: int = _f(lo=0, hi=1_000_000)
    kind: str = _f(default="polygon")
    vertices_m: tuple[tuple[float, float], ...] = _f("vertices_km", KM, default=())
    holes_m: tuple[tuple[tuple[float, float], ...], ...] = _f("holes_km", KM, default=())
    center_m: tuple[float, float] | None = _f("center_km", KM, default=None)
    radius_m: float | None = _f("radius_km", KM, default=None, lo=limits.MIN_POSITIVE, hi=2000.0)
    pattern: str | None = _f(default=None)
    spacing_m: float = _f("spacing_km", KM, default=5 * KM, lo=limits.MIN_POSITIVE, hi=2000.0)
    direction_rad: float = _f("direction_deg", DEG, default=0.0, lo=-3600.0, hi=3600.0)
    airfield: str | None = _f(default=None)
    landing: str | None = _f(default=None)
    #: expanding square only: fly the second, 45-degree-rotated search too (Fig. 6).
    second_search: bool = _f(default=True)

    def __post_init__(self) -> None:
        from poc_env.theory.regions import CircleRegion, PolygonRegion

        _coerce(self)
        _choice("kind", self.kind, ("polygon", "circle"))
        pattern = self.pattern or ("parallel" if self.kind == "polygon" else "sector")
        _choice("pattern", pattern, PATTERNS)
        if self.kind == "polygon" and pattern != "parallel":
            raise ConfigError("pattern", pattern, "'parallel' for a polygon region")
        object.__setattr__(self, "pattern", pattern)
        name = f"region {self.id}"
        if self.kind == "polygon":
            for key in ("vertices_m", "holes_m"):
                if not isinstance(getattr(self, key), (list, tuple)):
                    raise ConfigError(_yaml_key(RegionSpec, key), getattr(self, key), "a list")
            geom = PolygonRegion(self.vertices_m, self.holes_m, name=name).geometry
            x0, y0, x1, y1 = geom.bounds
            extent = max(x1 - x0, y1 - y0)
        else:
            if self.center_m is None:
                raise ConfigError("center_km", None, "[x, y] of the circle's centre")
            object.__setattr__(self, "center_m", _vec2("center_km", self.center_m))
            if self.radius_m is None:
                raise ConfigError("radius_km", None, "a number in (0, 2000] for a circle")
            CircleRegion(self.center_m, self.radius_m, name=name)
            extent = 2 * self.radius_m
        if extent / self.spacing_m > MAX_LINES:
            raise ConfigError(
                "spacing_km",
                self.spacing_m / KM,
                f"a spacing of at least {extent / MAX_LINES / KM:.3g} km for {name} "
                f"(at most {MAX_LINES} lines across its {extent / KM:.4g} km)",
            )

    def region(self):
        """The region object (``PolygonRegion`` or ``CircleRegion``)."""
        from poc_env.theory.regions import CircleRegion, PolygonRegion

        if self.kind == "polygon":
            return PolygonRegion(self.vertices_m, self.holes_m)
        return CircleRegion(self.center_m, self.radius_m)  # type: ignore[arg-type]

    def track(self, start=None):
        """Waypoints of this region's pattern (a :class:`~poc_env.theory.patterns.Track`)."""
        from poc_env.theory import patterns

        if self.pattern == "parallel":
            return patterns.parallel_search(
                self.region().geometry, self.spacing_m, self.direction_rad, start=start
            )
        if self.pattern == "sector":
            return patterns.sector_search(
                self.center_m,
                self.radius_m,
                spacing_m=self.spacing_m,
                rotation_rad=self.direction_rad,
            )
        if self.pattern == "expanding_square":
            return patterns.expanding_square(
                self.center_m, self.spacing_m, self.radius_m, second_rotated=self.second_search
            )
        return patterns.spiral_search(self.center_m, self.radius_m)


@dataclass(frozen=True)
class RegionPlan:
    """A set of regions, one per UAV, for a scenario (``configs/regions/*.yaml``)."""

    name: str = _f()
    regions: tuple[RegionSpec, ...] = _f()
    scenario: str | None = _f(default=None)
    description: str = _f(default="")

    def __post_init__(self) -> None:
        _coerce(self)
        if not isinstance(self.regions, (list, tuple)) or not self.regions:
            raise ConfigError("regions", self.regions, "a list of at least one region")
        ids = [r.id for r in self.regions]
        if len(set(ids)) != len(ids):
            raise ConfigError("regions", ids, "regions with distinct ids")


def load_regions(source: str | os.PathLike[str]) -> RegionPlan:
    """Load a region plan by built-in name (``configs/regions/NAME.yaml``) or YAML path."""
    text = str(source)
    names = sorted(p.stem for p in (CONFIG_DIR / "regions").glob("*.yaml"))
    # a built-in by its name only: never a path joined under configs/regions (an absolute
    # path or ../ would leave it), so a too-long path is the OSError of the user's own file
    path = CONFIG_DIR / "regions" / f"{text}.yaml" if text in names else Path(text)
    if not path.is_file():
        raise ConfigError("regions", text, f"a YAML file or one of {names}")
    data = read_yaml(path, "regions")
    data.setdefault("name", path.stem)
    return _from_mapping(RegionPlan, data, "regions")


@dataclass(frozen=True)
class SurveyRow:
    """Table 4 / 5 analog row for one UAV."""

    id: int
    pattern: str
    spacing_km: float
    direction_deg: float
    track_length_km: float
    search_length_km: float
    pod: float
    poc: float
    pos: float
    pos_flown: float
    flight_time_h: float
    feasible: bool


@dataclass(frozen=True)
class SurveyResult:
    scenario: str
    regions: str
    rows: tuple[SurveyRow, ...]
    posc: float
    posc_flown: float
    bound: float
    ceiling: float
    effort_km2: float
    tracks: tuple[np.ndarray, ...]
    takeoff_m: tuple[tuple[float, float], ...]
    landing_m: tuple[tuple[float, float], ...]

    def table(self) -> str:
        """The report as fixed-width text."""
        head = (
            f"{'No.':>3} {'pattern':<16} {'S/km':>6} {'dir/deg':>7} {'track/km':>9} {'legs/km':>8} "
            f"{'POD':>7} "
            f"{'POC':>7} {'POS':>7} {'POS flown':>9} {'time/h':>7} {'ok':>3}"
        )
        lines = [head, "-" * len(head)]
        for r in self.rows:
            lines.append(
                f"{r.id:>3} {r.pattern:<16} {r.spacing_km:>6.1f} {r.direction_deg:>7.1f} "
                f"{r.track_length_km:>9.1f} {r.search_length_km:>8.1f} {r.pod:>7.4f} "
                f"{r.poc:>7.4f} {r.pos:>7.4f} "
                f"{r.pos_flown:>9.4f} {r.flight_time_h:>7.2f} {'yes' if r.feasible else 'NO':>3}"
            )
        lines.append("-" * len(head))
        lines.append(
            f"POS_C = {self.posc:.4f} (eq. 10 x POC)   flown: {self.posc_flown:.4f}   "
            f"physical optimum for the same effort ({self.effort_km2:,.0f} km^2): "
            f"{self.bound:.4f}\n(ceiling for any sensor of this sweep width: {self.ceiling:.4f})"
        )
        return "\n".join(lines)

    def to_csv(self) -> str:
        buf = io.StringIO()
        fields = list(SurveyRow.__dataclass_fields__)
        w = csv.DictWriter(buf, fieldnames=[*fields, "posc", "posc_flown", "bound", "ceiling"])
        w.writeheader()
        for r in self.rows:
            row: dict[str, Any] = {k: getattr(r, k) for k in fields}
            row.update(
                posc=self.posc, posc_flown=self.posc_flown, bound=self.bound, ceiling=self.ceiling
            )
            w.writerow(row)
        return buf.getvalue()


def run_survey(
    scenario: Scenario | str = "paper_6_1",
    regions: RegionPlan | str | None = None,
    map_file: str | os.PathLike[str] | None = None,
    prior: np.ndarray | None = None,
) -> SurveyResult:
    """Score a region plan on a scenario: the Table 4 / 5 analog with the bound."""
    sc = load_scenario(scenario)
    plan = (
        regions
        if isinstance(regions, RegionPlan)
        else load_regions(regions or f"{sc.name}_polygons")
    )
    grid = Grid.from_config(sc.map)
    if prior is None:
        prior = build_prior(sc.map, map_file)
    w = sc.sensor.sweep_width_m
    law = sc.sensor.law
    s = sc.sensor.samples_per_cell
    from poc_env.sim.routing import ZoneRouter
    from poc_env.theory.regions import cell_overlap

    takeoffs, landings = _airfields_for(sc, plan)
    router = ZoneRouter.for_scenario(sc)
    tracks, pods, members, lengths, legs = [], [], [], [], []
    taken = None
    for spec, start, end in zip(plan.regions, takeoffs, landings):
        region = spec.region()
        tr = spec.track(start=start)
        # eq. 20: the pattern's legs cut to the parts outside the no-fly zones, joined by the
        # shortest way round (issue 24: survey plans flew through them); timed and scored so
        tracks.append(router.reroute([start, *tr.waypoints, end])[1:-1] if router.active
                      else tr.waypoints)  # fmt: skip
        lengths.append(tr.length_m)
        legs.append(tr.search_length_m)
        geom = region.geometry  # exclusive part: what earlier UAVs' regions do not hold
        members.append(cell_overlap(geom.difference(taken) if taken is not None else geom, grid))
        taken = geom if taken is None else taken.union(geom)
        if spec.pattern == "parallel":  # C = W / S (eq. 9): eq. 10 for the inverse-cube law
            pods.append(float(pod_from_coverage(parallel_coverage(w, spec.spacing_m), law)))
        else:
            pods.append(float(pod_from_coverage(w * tr.length_m / region.area_m2, law)))
    poc_i, pos_i, j = swarm_pos(np.array(members), np.array(pods), prior)
    belief = grid.refine(prior, s)
    flown = []
    cutoff = sc.sensor.cutoff_sweep_widths * w
    for wp in tracks:
        flown.append(sweep_track(belief, grid, s, wp, w, law, cutoff))
    rows = []
    for k, spec in enumerate(plan.regions):
        t = flight_time_s(
            takeoffs[k], tracks[k], landings[k], sc.uav.cruise_speed_mps, sc.uav.search_speed_mps
        )
        rows.append(
            SurveyRow(
                id=spec.id,
                pattern=spec.pattern or "",
                spacing_km=spec.spacing_m / KM,
                direction_deg=float(np.degrees(spec.direction_rad)),
                track_length_km=lengths[k] / KM,
                search_length_km=legs[k] / KM,
                pod=pods[k],
                poc=float(poc_i[k]),
                pos=float(pos_i[k]),
                pos_flown=float(flown[k]),
                flight_time_h=t / 3600.0,
                feasible=bool(is_feasible(t, sc.uav.endurance_s, sc.uav.usable_fraction)),
            )
        )
    effort = w * float(np.sum(lengths))
    bound = physical_optimum(prior, grid.cell_area_m2, effort, law).pos
    return SurveyResult(
        scenario=sc.name,
        regions=plan.name,
        rows=tuple(rows),
        posc=float(j),
        posc_flown=float(np.sum(flown)),
        bound=bound,
        ceiling=physical_optimum(prior, grid.cell_area_m2, effort, "definite_range").pos,
        effort_km2=effort / KM**2,
        tracks=tuple(tracks),
        takeoff_m=tuple(takeoffs),
        landing_m=tuple(landings),
    )


def _airfields_for(sc: Scenario, plan: RegionPlan):
    """Take-off and landing point of each region's UAV: its named airfield, else fleet order."""
    if len(plan.regions) > sc.n_uavs:
        raise ConfigError("regions", len(plan.regions), f"at most the scenario's {sc.n_uavs} UAVs")
    takeoffs, landings = [], []
    for k, spec in enumerate(plan.regions):
        if spec.airfield is None:
            takeoffs.append(sc.takeoff_m[k])
            landings.append(sc.landing_m[k])
        else:
            takeoffs.append(sc.airfield(spec.airfield).position_m)
            landings.append(sc.airfield(spec.landing or spec.airfield).position_m)
    return takeoffs, landings


#: The files :func:`write_survey` writes into its folder (the figure only with a prior).
SURVEY_FILES = ("survey.csv", "survey.txt", "survey.png")


def write_survey(
    result: SurveyResult,
    out_dir: str | os.PathLike[str],
    prior=None,
    scenario: Scenario | None = None,
    plan: RegionPlan | None = None,
) -> list[Path]:
    """Write ``survey.csv``, ``survey.txt`` and the figure ``survey.png`` into ``out_dir``."""
    out = Path(out_dir)
    csv_name, txt_name, png_name = SURVEY_FILES
    paths = [
        write_text_atomic(out / csv_name, result.to_csv()),
        write_text_atomic(out / txt_name, result.table() + "\n"),
    ]
    if prior is not None and scenario is not None and plan is not None:
        from poc_env.viz.plots import plot_survey

        paths.append(plot_survey(result, scenario, plan, prior, out / png_name))
    return paths


def survey_plan(
    result: SurveyResult,
    scenario: Scenario,
    regions: RegionPlan,
    prior: np.ndarray,
    *,
    map_source: str = "builtin",
    origin_deg: Any = None,
    projection: str = "aeqd",
    zone: int | None = None,
) -> dict[str, Any]:
    """A survey as a schema-2 plan (:mod:`poc_env.agents.mission.plan`), so that ``poc-env
    export`` writes its missions, KML, GeoJSON and map report.

    Per UAV: ``rectangle`` null, ``waypoints_m`` the region's pattern (what the survey timed:
    take-off field, the pattern, landing field), ``areas_m`` the region's outline (a circle as
    its polygon; holes are not drawn), ``spacing_m``, ``track_length_m`` (the pattern's length),
    ``flight_time_s`` (eq. 17), ``pod``, ``poc``, ``pos`` (eq. 10 x POC, the survey's columns),
    ``feasible``, plus ``pattern`` and ``pos_flown``. Top level: ``posc`` the survey's POS_C,
    ``upper_bound`` its physical optimum for the same effort, ``optimizer`` {``name``:
    ``survey``, ``settings`` {``regions``}}, and the plan's geography (flight, operating area,
    no-fly zones, airfields, bounds and, with ``origin_deg``, the ``crs``) as
    :func:`poc_env.agents.planning.planner.make_plan` records it.
    """
    from poc_env.agents.mission.plan import RECTANGLE_RULE, SCHEMA
    from poc_env.agents.planning.geography import (
        check_terrain,
        plan_geography,
        probability,
        scenario_crs,
    )

    # the scenario's map.origin_deg as `poc-env plan` reads it (issue 24: ignored here)
    crs = scenario_crs(scenario, origin_deg, projection, zone)
    uavs = []
    for k, (spec, row) in enumerate(zip(regions.regions, result.rows)):
        geom = spec.region().geometry
        outline = [[float(x), float(y)] for x, y in list(geom.exterior.coords)[:-1]]
        uavs.append(
            {
                "id": int(spec.id),
                "rectangle": None,
                "spacing_m": float(spec.spacing_m),
                "takeoff_m": [float(v) for v in result.takeoff_m[k]],
                "landing_m": [float(v) for v in result.landing_m[k]],
                "waypoints_m": np.asarray(result.tracks[k], dtype=float).tolist(),
                "track_length_m": float(row.track_length_km * KM),
                "flight_time_s": float(row.flight_time_h * 3600.0),
                "pod": probability(row.pod),
                "poc": probability(row.poc),
                "pos": probability(row.pos),
                "feasible": bool(row.feasible),
                "areas_m": [outline],
                "pattern": row.pattern,
                "pos_flown": probability(row.pos_flown),
            }
        )
    return check_terrain(
        {
            "schema": SCHEMA,
            "scenario": scenario.name,
            "seed": 0,
            "map_source": map_source,
            "optimizer": {"name": "survey", "settings": {"regions": regions.name}},
            "runtime_s": 0.0,
            "posc": probability(result.posc),
            "upper_bound": probability(result.bound),
            "rectangle_rule": RECTANGLE_RULE,
            "uavs": uavs,
            **plan_geography(scenario, prior, crs),
        },
        scenario,
        prior,  # orbits that do not fit: the patterns trimmed, as plan's (i24-missionfix)
    )
