"""The allocation planner's tuning knobs as one value, and its effort levels (issue 24).

:class:`PlanOptions` holds every choice of :func:`poc_env.agents.planning.allocation.
make_allocation_plan` and of the starts it builds (:mod:`~poc_env.agents.planning.coverage_boxes`,
:mod:`~poc_env.agents.planning.excursions`) that used to be a module global. It is passed down
explicitly (``make_allocation_plan(..., options=...)``, ``box_routes(..., options=...)``); its
defaults are the planner's as it was, so ``PlanOptions()`` plans what the module globals
planned, bit for bit. Change a copy with :func:`dataclasses.replace`; fields are checked on
construction (:class:`~poc_env.errors.ConfigError` naming the field, the value and what is
allowed).

**Effort levels** (:meth:`PlanOptions.preset`): a planning officer plans a sortie once and can
wait for a better one. ``"default"`` is the planner of ``allocation_plan`` and ``poc-env plan``
(within the issue's 2 s on ``paper_6_2`` and 10 s for 24 UAVs on 160 x 160 cells);
``"standard"`` (i24-fastpolish, i24-cheapolish) is the default plan polished (1 pass with the
grade moves, 2 of the second polish at radii W/8-2W with the block moves on windows of 1 and
2 lawnmower lines) on maps of at most 80 cells a side -- on larger ones the same stages, the
second polish up to 12 passes, within a work budget of 12 million candidate steps
(i24-bigpolish: about a minute of one core at 160 x 160 cells and 24 UAVs; docs/PLANNER.md,
"Standard on big maps") --: within 2 s on ``paper_6_2`` (2.9 times
the default's CPU time, median; docs/PLANNER.md, "Cheaper candidates (i24-cheapolish)"; before
it 2 passes and 1 of the second polish at the polish's radii, flown 0.887 of the rule-aware
bound on the 50 reported priors against the default's 0.852: "A faster polish
(i24-fastpolish)"), policy ``allocation_plan_standard``;
``"thorough"`` is the combination that gained most on the validation priors within about a
minute on ``paper_6_2`` and two on ``large_400`` (one thread; docs/PLANNER.md, "Effort levels
(i24-effort, 2026-11-28)"), with 6 passes of the polish by the environment's own sensor model
(:mod:`~poc_env.agents.planning.polish`; "Polish by the environment's model (i24-polish,
2026-11-28)") and its grade moves ("Grading and the last 0.007 (i24-grade, 2026-11-28)"):
``poc-env plan --effort thorough``, policy ``allocation_plan_thorough``. With the polish it
took 32 s (median; at most 58 s) a plan on ``paper_6_2`` and 38 s (at most 165 s) on
``large_400``, one thread at load 1-6, over the 50 reported priors each; with the grade moves
88 s (at most 124 s) on ``paper_6_2`` at load 6.4-8.5 (1.3-1.4 times the time without them,
interleaved in one process at that load) and
210 s (at most 287 s) on ``large_400`` at load
4.2-8.5 (20 priors; 1.13 times the time without them, interleaved at load 3.2-3.4). With the
second polish and its block moves (``polish_lines``; "Block moves and a second polish
(i24-lines, 2026-11-28)") 71 s (at most 113 s) on ``paper_6_2`` at load 4.4-7.5 over the 50
reported priors: 2.2-2.5 times the CPU time without it (interleaved, validation priors 5002
and 5003: 16.4 -> 36.4 s, 14.1 -> 34.8 s).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

from poc_env.errors import ConfigError

#: the effort levels of :meth:`PlanOptions.preset`.
EFFORTS = ("default", "standard", "thorough")


def _positive_tuple(name: str, value: Any, *, integer: bool = False, low: float = 0.0,
                    high: float = math.inf, empty: bool = False) -> None:  # fmt: skip
    kind = "integers" if integer else "numbers"
    allowed = f"a tuple of {kind} in ({low:g}, {high:g}]" + ("" if empty else ", not empty")
    if not isinstance(value, tuple) or (not value and not empty):
        raise ConfigError(f"options.{name}", value, allowed)
    for v in value:
        bad = isinstance(v, bool) or not isinstance(v, int | float)
        if integer and not isinstance(v, int):
            bad = True
        if bad or not math.isfinite(float(v)) or not (low < float(v) <= high):
            raise ConfigError(f"options.{name}", value, allowed)


def _number(name: str, value: Any, low: float, high: float, *, integer: bool = False,
            closed_low: bool = True) -> None:  # fmt: skip
    lo = "[" if closed_low else "("
    allowed = f"{'an integer' if integer else 'a number'} in {lo}{low:g}, {high:g}]"
    bad = isinstance(value, bool) or not isinstance(value, int | float)
    if integer and not isinstance(value, int):
        bad = True
    if bad or not math.isfinite(float(value)):
        raise ConfigError(f"options.{name}", value, allowed)
    v = float(value)
    if v > high or v < low or (v == low and not closed_low):
        raise ConfigError(f"options.{name}", value, allowed)


@dataclass(frozen=True)
class PlanOptions:
    """The allocation planner's choices (module docstring). Defaults: the planner of
    ``allocation_plan``, unchanged."""

    # --- make_allocation_plan (agents/planning/allocation.py) ---
    #: numbers of coverage layers ``K`` tried (step 2 of the allocation planner).
    levels: tuple[int, ...] = (3, 4, 6)
    #: effort scales ``eta`` tried (step 5; the plan keeps the one of highest planned POS).
    etas: tuple[float, ...] = (0.3, 0.4, 0.5, 0.65)
    #: the share of 0.85 T a route of the allocation start may fill.
    margin: float = 1.0
    #: passes of :func:`~poc_env.agents.planning.refine.refine_routes` (0: none).
    refine: int = 4
    #: the starts refined (best first by W x length per cell).
    refine_starts: int = 2
    #: a start is refined too only if its W x length per cell score is within this share of
    #: the best start's.
    refine_within: float = 0.9
    #: ... and (True) within that share of the best of the starts to refine by the
    #: environment's model too, where the boxes are graded and sampled
    #: (:meth:`sampled_here`); i24-quality3.
    refine_sampled: bool = False
    #: margins on d_s (eq. 21) and the communication range (eq. 24) of the refinement's
    #: airspace check.
    separation_margin: float = 2.0
    range_margin: float = 0.9
    #: the plan is picked among the starts by sampled POS less the environment's violation
    #: penalty at the planned positions (:func:`~poc_env.agents.planning.allocation.
    #: violation_penalty`) where the boxes are graded and sampled (i24-quality3); False: by
    #: POS alone.
    airspace_penalty: bool = False
    #: the penalty counts violations within ``penalty_separation`` x d_s (eq. 21) and with fewer
    #: neighbours than needed within ``penalty_range`` x the communication range (eq. 24).
    penalty_separation: float = 2.0
    penalty_range: float = 0.9
    #: the penalty's weight on the reward's rate (1: the reward's own exchange rate).
    penalty_weight: float = 1.0
    #: also start from the greedy rectangle plan, and from the coverage boxes.
    greedy_start: bool = True
    box_start: bool = True
    #: also start from the relaxation patches (:mod:`~poc_env.agents.planning.relax_patches`:
    #: each UAV its own sector of an allocation with UAVs dedicated to a distance, laid
    #: graded; i24-relax; off: measured below the boxes on ``large_400``).
    relax_start: bool = False
    #: UAVs a start leaves without a route are given coverage boxes on the mass the start's
    #: routes leave (i24-fleet: a larger fleet must not leave UAVs idle while reachable mass
    #: remains; :mod:`~poc_env.agents.planning.allocation`, step 6).
    fill_idle: bool = True
    #: the exchange passes (single boxes, then chained) of that fill's coverage boxes
    #: (``rounds`` and ``chain_rounds`` of the boxes start; 0: the greedy assignment alone).
    fill_rounds: int = 0
    #: a filled route whose planned flight breaks eq. 21 with a UAV already flying (the
    #: deconfliction's measure, :func:`~poc_env.agents.planning.deconflict.conflicts`) is
    #: dropped (i24-fleet), its UAV filled again clear of the others up to ``FILL_TRIES``
    #: times before it stays idle (i24-stagger). On by default, safety first as the lanes (a
    #: planning officer cannot send converging routes): on the audit's 500 km scenario at 48
    #: UAVs it costs 0.018 of planned POS (0.9142 -> 0.8962 with the refill; 0.8861 with the
    #: drop alone; 0.8223 before the fill), and the flight has 29 collision steps, where
    #: without it the filled routes added 210 planned conflict pair-steps and the flight 177
    #: collision steps (44 before the fill).
    fill_apart: bool = True
    #: a plan that leaves a UAV without a route (the fleet larger than it uses) is compared
    #: with the plan of half the fleet (planned alike, :meth:`~poc_env.config.Scenario.
    #: with_uavs`) with the other UAVs filled, as :func:`~poc_env.agents.planning.allocation.
    #: plan_fleets`' floor: the one of more planned POS kept (i24-chain). Off in the
    #: ``standard`` and ``thorough`` presets (not measured there: it would polish a second plan).
    half_fleet: bool = True
    #: with ``half_fleet``, a plan of at least this many UAVs that leaves a UAV without a route
    #: is also compared with the plan of three quarters of its fleet (planned alike, with
    #: ``half_fleet`` only), its other UAVs filled (i24-monotone; 0: never). The half fleet
    #: alone let 32 UAVs plan less than 24 on the audit's 500 km scenario (32's half is 16,
    #: whose routes leave the fill nothing it flies clear of them; 24's is 12), 64 less than
    #: 48. From 32: at 24 UAVs on 160 x 160 cells it would plan 18 more UAVs, about 1.8 times
    #: the CPU, past issue 24's 10 s (results/plan_scale/i24-monotone). Off (0) by default:
    #: at 32 UAVs the plan it keeps there flew 28 eq. 21 collision UAV-steps away from the
    #: fields where the half fleet's flew none (safety before monotonicity, as i24-stagger);
    #: ``PlanOptions(three_quarter_from=32)`` turns it on from 32 UAVs.
    three_quarter_from: int = 0
    #: the plan's own routes held to the fill's clearance where it costs little (i24-ownclear):
    #: the routes go through the fill's check (:func:`~poc_env.agents.planning.deconflict.
    #: apart` at ``FILL_WITHIN``), the dropped UAVs filled, and the cleared plan is kept if its
    #: planned POS less the environment's violation penalty at the planned positions
    #: (:func:`~poc_env.agents.planning.allocation.violation_penalty`, the reward's exchange
    #: rate) is at least the plan's own and it flies as many UAVs (waived in the half fleet's
    #: plan, whose idle UAVs the larger fleet's fill refills). Needs ``fill_apart``. On in
    #: every preset (measured with the default; the ``standard`` digests are unchanged).
    own_apart: bool = True
    #: the relaxation patches' effort scales ``eta`` (the share of pattern time on lines
    #: their allocation assumes; the start keeps the one of most W x length per cell) ...
    relax_etas: tuple[float, ...] = (0.65, 0.75, 0.85, 0.95, 1.0)
    #: ... and the shares of its coverage each UAV's patch is laid at (each UAV keeps the one
    #: of most POS on its patch; less coverage, shorter routes).
    relax_scales: tuple[float, ...] = (1.0, 0.9, 0.8, 0.7, 0.6, 0.5)

    # --- coverage boxes (agents/planning/coverage_boxes.py) ---
    #: line spacings tried, in sweep widths.
    spacings: tuple[float, ...] = (1.0, 1.5, 2.0, 3.0, 4.0)
    #: spacings below one sweep width, tried too where boxes are searched cell by cell.
    dense_spacings: tuple[float, ...] = (0.75,)
    #: boxes are searched on blocks of cells so that a side has at most this many blocks.
    max_cells: int = 80
    #: recompute candidates lazily (same routes; False recomputes every field's each round).
    lazy: bool = True
    #: passes of the single-box exchange.
    rounds: int = 2
    #: shares of the budget the first of two chained lawnmowers is searched with (): one.
    chain: tuple[float, ...] = (0.35, 0.55)
    #: chains tried in the greedy and exchange steps too (True) or only in final passes.
    chain_early: bool = False
    #: final exchange passes with chains.
    chain_rounds: int = 2
    #: spacings tried for the second chained lawnmower; (): all of the spacings.
    chain_spacings: tuple[float, ...] = ()
    #: a route that does not fit flies its first dropped line in part (True) or drops it.
    part: bool = True
    #: halvings of the bisection for the part of a line that fits.
    part_steps: int = 12
    #: share one coverage's gain tables among the lawnmowers searched against it, and derive
    #: a second lawnmower's from its first's where the first flies (i24-speed) (same routes;
    #: False recomputes them per lawnmower, slower; for the tests).
    share_tables: bool = True
    #: box orientations tried besides the map's axes (degrees; i24-quality4).
    angles: tuple[float, ...] = ()
    #: also try, per candidate, boxes turned to the gain's principal axis (i24-quality4),
    #: rounded to ``axis_step`` degrees, in a window grown by ``axis_grow`` of the box a side.
    axis: bool = False
    axis_step: float = 15.0
    axis_grow: float = 0.5
    #: excursions (take-off -> P -> Q -> landing) as candidates too (i24-quality4); the best
    #: ``excursion_top`` first points paired, the ``excursion_exact`` best pairs scored.
    excursions: bool = False
    excursion_top: int = 12
    excursion_exact: int = 6
    #: lines at graded spacing across each box (:func:`~poc_env.agents.planning.
    #: coverage_boxes.graded_offsets`; i24-quality3) where boxes are searched cell by cell:
    #: False evenly (as before), True graded, "both" each candidate both ways.
    graded: bool | str = False
    #: the least spacing of graded lines (sweep widths) and the water-filling's step (lines).
    graded_min: float = 0.5
    graded_step: float = 0.25
    #: candidates scored by the environment's detection model (i24-quality3) where boxes are
    #: searched cell by cell; False: W x length per cell.
    sampled: bool = False
    #: second chained lawnmowers rescored by the sampled model: the best few by the cell model.
    sampled_top: int = 2
    #: passes of :func:`~poc_env.agents.planning.polish.polish_routes` on the chosen routes
    #: (0: none): a local search on the waypoints scored by the environment's own sensor
    #: model (the plan's ``posc``), after the start is picked (i24-polish); not on maps with
    #: no-fly zones.
    polish: int = 0
    #: the polish's move radii, in sweep widths.
    polish_radii: tuple[float, ...] = (0.25, 0.5, 1.0, 2.0)
    #: plans polished: the chosen one and the next best of the starts (refined or not); the
    #: best polished one is kept.
    polish_starts: int = 1
    #: the polish also tries its ``grade`` moves (a run of consecutive lawnmower lines
    #: squeezed or spread together: :data:`~poc_env.agents.planning.polish.KINDS`; i24-grade).
    polish_grade: bool = False
    #: passes of a second polish after it (0: none), its moves those of the polish and the
    #: ``block`` moves (a run of lawnmower lines translated as one across or along the lines:
    #: :data:`~poc_env.agents.planning.polish.ALL_KINDS`; i24-lines).
    polish_lines: int = 0
    #: the second polish's move radii, in sweep widths.
    polish_lines_radii: tuple[float, ...] = (0.25, 0.5, 1.0, 2.0)
    #: the block moves' windows: waypoints translated together (2 per lawnmower line;
    #: :data:`~poc_env.agents.planning.polish.BLOCK_WINDOWS`; i24-cheapolish).
    polish_lines_windows: tuple[int, ...] = (2, 4, 6, 8)
    #: the block moves' radii, in sweep widths (empty: ``polish_lines_radii``; i24-cheapolish).
    polish_lines_block_radii: tuple[float, ...] = ()
    #: the polish stages' screen (i24-fast2s; 0: off): a waypoint's or a window's candidates
    #: scored first with the cut-off :attr:`polish_screen_cutoff` (fewer sample points: an
    #: approximate gain) and only this many of the best of them exactly
    #: (:func:`~poc_env.agents.planning.polish.screened_gains`).
    polish_screen: int = 0
    #: the screen's cut-off, in sweep widths (at or above the sensor's
    #: ``cutoff_sweep_widths``: the sensor's own, the screen then ranks by the exact gains).
    polish_screen_cutoff: float = 2.0
    #: passes of a third polish after the polishes (0: none), with the box moves only (a
    #: route's box translated, stretched or turned as one, an airfield's group translated or
    #: turned together: :data:`~poc_env.agents.planning.polish.BOX_KINDS`; i24-boxes).
    polish_boxes: int = 0
    #: the box moves' translations, in sweep widths.
    polish_boxes_radii: tuple[float, ...] = (2.0, 4.0, 8.0, 16.0)
    #: passes of the regrade (0: none; i24-regrade): each route's runs of lawnmower lines
    #: re-spaced jointly in the environment's sensor model -- water-filled across the run,
    #: then a coordinate search per line, with one line more or fewer tried
    #: (:func:`~poc_env.agents.planning.regrade.regrade_routes`); a polish stage.
    regrade: int = 0
    #: where the regrade runs: ``"first"`` before the polish (on the plan as the starts laid
    #: it), ``"between"`` after the polish and before the second polish, ``"end"`` after
    #: every polish stage.
    regrade_at: str = "first"
    #: polish only maps of at most this many cells a side (0: any size; i24-fastpolish: a
    #: deterministic size rule, no clock, so a preset keeps its time on large maps; elsewhere
    #: the plan is the unpolished one and its settings say why).
    polish_max_cells: int = 0
    #: on maps of more than :attr:`polish_max_cells` cells a side the polish stages run anyway
    #: within this work budget (i24-bigpolish; 0: they are skipped there, as before): they stop
    #: once they have scored this many candidate steps together (the candidates' legs cut into
    #: steps of at most a cell: the scoring kernel's work; a count, not a clock, so plans are
    #: reproducible), with :attr:`polish_big_lines` passes of the second polish.
    polish_big_work: int = 0
    #: passes of the second polish on such maps (0: :attr:`polish_lines`); the budget usually
    #: stops it first.
    polish_big_lines: int = 0
    #: also make the default plan (``PlanOptions()`` with this value's levels, margin, refine
    #: and starts) and keep it if it plans more POS: a plan of these options then never plans
    #: less POS than the default's, at the default's planning time more.
    also_default: bool = False
    #: polish on maps with no-fly zones too (i24-zonepolish): no candidate may enter a zone or
    #: cut the router's clearance (:func:`~poc_env.agents.planning.polish.zone_guard`); False:
    #: the polish is skipped there, as it was before.
    polish_zones: bool = True
    #: the zone credit (i24-zonepolish): the planners' objective counts the prior inside and
    #: near the zones by the share of each cell within this lateral reach, in sweep widths, of
    #: the keep-out area's outside (:meth:`~poc_env.sim.routing.ZoneRouter.reach_share`); 0.5:
    #: the sweep's half width, the eq. 10 model.
    zone_reach: float = 0.5
    #: "nothing", as a share of the prior's mass (i24-smallfix, F1): among the candidate plans
    #: within it of the best planned POS the one of least total flight time is kept (each with
    #: its UAVs below ``gain_per_hour`` kept home first); 0: neither that nor
    #: ``gain_per_hour`` (every route flown, the first of the highest kept, as before F1).
    #: Until i24-gainhour it was also a loss budget for the whole plan for the UAVs kept home
    #: (on the 500 km scenario at 48 UAVs three flew 7.7 h for 1.2e-4 together,
    #: results/audit/dayaudit2, G3); ``gain_per_hour`` is that rule now.
    nothing: float = 1e-4
    #: the floor a flying UAV must add, as a share of the prior's mass **per eq. 17 flight
    #: hour** (i24-gainhour, G3): a UAV whose route adds less than this times its own flight
    #: hours to the plan's POS stays home. Every flying UAV's marginal POS is computed; those
    #: below their floor are tried longest flight first, each against the plan left by the
    #: ones before, so every UAV that flies adds its floor and the plan loses less than this
    #: times the flight hours it saves; 0: every route flies (docs/PLANNER.md, "A floor per
    #: flight hour").
    gain_per_hour: float = 1e-4

    def __post_init__(self) -> None:
        _positive_tuple("levels", self.levels, integer=True, high=64)
        _positive_tuple("etas", self.etas, high=1.0)
        _number("margin", self.margin, 0.1, 1.0)
        _number("refine", self.refine, 0, 100, integer=True)
        _number("refine_starts", self.refine_starts, 1, 3, integer=True)
        _number("refine_within", self.refine_within, 0.0, 1.0)
        _number("separation_margin", self.separation_margin, 1.0, 10.0)
        _number("range_margin", self.range_margin, 0.1, 1.0)
        _positive_tuple("spacings", self.spacings, high=20.0)
        _positive_tuple("dense_spacings", self.dense_spacings, high=20.0, empty=True)
        _number("max_cells", self.max_cells, 8, 400, integer=True)
        _number("rounds", self.rounds, 0, 20, integer=True)
        _number("fill_rounds", self.fill_rounds, 0, 20, integer=True)
        _number("three_quarter_from", self.three_quarter_from, 0, 64, integer=True)
        _positive_tuple("chain", self.chain, high=0.95, empty=True)
        _number("chain_rounds", self.chain_rounds, 0, 20, integer=True)
        _positive_tuple("chain_spacings", self.chain_spacings, high=20.0, empty=True)
        _number("part_steps", self.part_steps, 1, 40, integer=True)
        _positive_tuple("angles", self.angles, high=180.0, empty=True)
        if any(float(a) % 180.0 == 0.0 for a in self.angles):
            raise ConfigError("options.angles", self.angles, "angles in (0, 180) degrees")
        _number("axis_step", self.axis_step, 0.0, 45.0, closed_low=False)
        _number("axis_grow", self.axis_grow, 0.0, 10.0)
        _number("excursion_top", self.excursion_top, 1, 1000, integer=True)
        _number("excursion_exact", self.excursion_exact, 1, 1000, integer=True)
        if not (self.graded is True or self.graded is False or self.graded == "both"):
            raise ConfigError("options.graded", self.graded, 'False, True or "both"')
        _number("graded_min", self.graded_min, 0.0, 4.0, closed_low=False)
        _number("graded_step", self.graded_step, 0.0, 1.0, closed_low=False)
        _number("sampled_top", self.sampled_top, 1, 100, integer=True)
        _number("polish", self.polish, 0, 100, integer=True)
        _number("polish_starts", self.polish_starts, 1, 6, integer=True)
        _number("polish_lines", self.polish_lines, 0, 100, integer=True)
        _positive_tuple("polish_radii", self.polish_radii, high=8.0)
        _positive_tuple("polish_lines_radii", self.polish_lines_radii, high=8.0)
        _positive_tuple("polish_lines_windows", self.polish_lines_windows, integer=True, high=16)
        _positive_tuple("polish_lines_block_radii", self.polish_lines_block_radii, high=8.0,
                        empty=True)  # fmt: skip
        _number("polish_boxes", self.polish_boxes, 0, 100, integer=True)
        _number("polish_screen", self.polish_screen, 0, 10000, integer=True)
        _number("polish_screen_cutoff", self.polish_screen_cutoff, 0.0, 100.0, closed_low=False)
        _number("polish_max_cells", self.polish_max_cells, 0, 100000, integer=True)
        _number("polish_big_work", self.polish_big_work, 0, 1e12, integer=True)
        _number("polish_big_lines", self.polish_big_lines, 0, 100, integer=True)
        _number("regrade", self.regrade, 0, 100, integer=True)
        _number("zone_reach", self.zone_reach, 0.0, 16.0, closed_low=False)
        _number("nothing", self.nothing, 0.0, 0.01)
        _number("gain_per_hour", self.gain_per_hour, 0.0, 0.01)
        if self.regrade_at not in ("first", "between", "end"):
            raise ConfigError("options.regrade_at", self.regrade_at, '"first", "between" or "end"')
        _positive_tuple("polish_boxes_radii", self.polish_boxes_radii, high=64.0)
        _positive_tuple("relax_etas", self.relax_etas, high=1.0)
        _positive_tuple("relax_scales", self.relax_scales, high=1.0)
        _number("penalty_weight", self.penalty_weight, 0.0, 100.0)
        _number("penalty_separation", self.penalty_separation, 1.0, 10.0)
        _number("penalty_range", self.penalty_range, 0.1, 1.0)
        flags = ("refine_sampled", "airspace_penalty", "greedy_start", "box_start", "lazy",
                 "relax_start", "fill_idle", "fill_apart", "half_fleet", "own_apart",
                 "chain_early",
                 "also_default", "part", "share_tables", "axis", "excursions", "sampled",
                 "polish_grade", "polish_zones")  # fmt: skip
        for name in flags:
            if not isinstance(getattr(self, name), bool):
                raise ConfigError(f"options.{name}", getattr(self, name), "true or false")

    def polish_here(self, nx: int, ny: int) -> bool:
        """Whether the polish stages run on a map of ``nx x ny`` cells
        (:attr:`polish_max_cells`)."""
        return not self.polish_max_cells or max(nx, ny) <= self.polish_max_cells

    def sampled_here(self, nx: int, ny: int) -> bool:
        """Whether graded lines and sampled scores apply on a map of ``nx x ny`` cells: where
        boxes are searched cell by cell (at most :attr:`max_cells` a side; on 24 UAVs over
        160 x 160 cells the sampled scores took 3.5 times the planning time, i24-quality3)."""
        return max(nx, ny) <= self.max_cells

    @classmethod
    def preset(cls, effort: str = "default") -> PlanOptions:
        """The options of an effort level (:data:`EFFORTS`): ``"default"`` the planner of
        ``allocation_plan``; ``"standard"`` the default plan polished within the issue's 2 s on
        ``paper_6_2``; ``"thorough"`` the combination chosen on the validation priors (module
        docstring)."""
        if effort == "default":
            return cls()
        if effort == "thorough":
            return cls(**THOROUGH)
        if effort == "standard":
            return cls(**STANDARD)
        raise ConfigError("effort", effort, f"one of {', '.join(EFFORTS)}")

    def changed(self) -> dict[str, Any]:
        """The fields that differ from the defaults (for plan.json)."""
        base = PlanOptions()
        return {
            f.name: getattr(self, f.name)
            for f in dataclasses.fields(self)
            if getattr(self, f.name) != getattr(base, f.name)
        }


#: the ``thorough`` effort level's changes to the defaults (chosen on validation priors:
#: docs/PLANNER.md, "Effort levels (i24-effort, 2026-11-28)").
THOROUGH: dict[str, Any] = {
    "graded": True,
    "sampled": True,
    "refine_sampled": True,
    "airspace_penalty": True,
    "angles": (45.0,),
    "excursions": True,
    "also_default": True,
    "polish": 6,  # i24-polish: docs/PLANNER.md, "Polish by the environment's model"
    "polish_grade": True,  # i24-grade: docs/PLANNER.md, "Grading and the last 0.007"
    # i24-lines: docs/PLANNER.md, "Block moves and a second polish"
    "polish_lines": 6,
    "polish_lines_radii": (0.125, 0.25, 0.5, 1.0, 2.0),
    # i24-chain: the half fleet is tried by the default plan only (here it would polish a
    # second plan; not measured at this level); also_default's default plan tries it
    "half_fleet": False,
}

#: the ``standard`` effort level's changes to the defaults (i24-fastpolish: the default plan
#: polished, the most POS within the issue's 2 s on ``paper_6_2``, chosen on its validation
#: priors: docs/PLANNER.md, "A faster polish (i24-fastpolish)"; its passes and candidates
#: chosen again by i24-cheapolish, "Cheaper candidates"); as chosen on maps of at most 80
#: cells a side, on larger ones within a work budget (i24-bigpolish).
STANDARD: dict[str, Any] = {
    "polish": 1,
    "polish_grade": True,
    # i24-cheapolish: fewer passes of the polish, more of the second at thorough's radii with
    # the block moves' windows that are kept (docs/PLANNER.md, "Cheaper candidates")
    "polish_lines": 2,
    "polish_lines_radii": (0.125, 0.25, 0.5, 1.0, 2.0),
    "polish_lines_windows": (2, 4),
    "polish_max_cells": 80,
    # i24-bigpolish: above 80 cells a side the same stages, the second polish up to 12 passes,
    # stopped after 12 million candidate steps scored (about 40 s of one core on the 500 km
    # scenario, 160 x 160 cells, 24 UAVs: docs/PLANNER.md, "Standard on big maps")
    "polish_big_work": 12_000_000,
    "polish_big_lines": 12,
    # i24-chain: the half fleet is tried by the default plan only (here it would polish a
    # second plan within a second budget; not measured at this level)
    "half_fleet": False,
}
