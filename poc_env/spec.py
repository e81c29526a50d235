"""The environment's contract tables, once: observation layouts, reward terms, info keys, tasks.

Every table of the environment's interface is a tuple here that the code reads (the observation
builders and spaces, the reward terms, the infos, the task registry), the tests read, and the
documentation is generated from (:func:`markdown`, written into ``docs/environment.md`` between
``<!-- spec:NAME -->`` markers by ``poc-env spec --write``; ``tests/envs/test_spec.py`` checks
the committed page equals the generated text).

* :data:`RASTER` and :data:`VECTOR`: the ``dict`` observation (``flat`` is the raster raveled
  in C order, then the vector); :data:`COMPASS`: the size-free ``compass`` observation every
  registered task uses.
* :data:`REWARD_TERMS`: the terms :func:`poc_env.sim.rewards.reward_terms` returns, in order.
* :data:`VIOLATION_FLAGS` and :data:`INFOS`: the per-agent info keys (:func:`info_keys`).
* :data:`SCENARIO_PARTS`, :data:`RANDOM_PARTS`, :data:`CONTROL_PARTS` and
  :data:`TASK_VERSIONS`: the registered task ids (:mod:`poc_env.tasks`), each with its own
  version.

Changing a row that changes what an agent observes or is rewarded, or how the swarm moves or
ends, adds a row to :data:`TASK_VERSIONS` for the tasks it touches (the versioning rule of
:mod:`poc_env.tasks`: the old ids stay registered with their old behaviour); the recorded
episodes (:mod:`poc_env.recorded`) fail until then.
"""

from __future__ import annotations

import argparse
import itertools
import re
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import NamedTuple

import numpy as np

#: The first release's version, which every task id had until versions became per task
#: (:data:`TASK_VERSIONS`); every id registered at it stays registered.
TASK_VERSION = 0


class Entry(NamedTuple):
    """One row of a contract table: a name, its shape (symbolic: ``N`` agents, ``ny x nx``
    cells), dtype, bounds and meaning."""

    name: str
    shape: str
    dtype: str
    low: float | None
    high: float | None
    meaning: str


def _e(name, meaning, low=0.0, high=1.0, shape="()", dtype="float32") -> Entry:
    return Entry(name, shape, dtype, low, high, meaning)


# -- observations --------------------------------------------------------------------------
#: Raster channels of the ``dict`` / ``flat`` observation, one ``(ny, nx)`` image each.
_CELLS = "(ny, nx)"
RASTER = (
    _e(
        "poc", "current POC of the cell / the largest cell POC of the episode's prior", shape=_CELLS
    ),
    _e("self", "1 in the cell holding this UAV (all 0 while it is outside the grid)", shape=_CELLS),
    _e("others", "1 in cells holding another flying UAV", shape=_CELLS),
    _e(
        "hazard",
        "1 where the cell centre is in a no-fly zone or above the threat limit",
        shape=_CELLS,
    ),
)
#: The state vector of every observation kind.
VECTOR = (
    _e("x", "position in the operating area, 0 .. 1 across it", -1.0, 2.0),
    _e("y", "position in the operating area, 0 .. 1 along it", -1.0, 2.0),
    _e("z", "altitude / ceiling"),
    _e("speed", "(v - v_min) / (v_max - v_min); 0 when v_min = v_max (a fixed-speed UAV)"),
    _e("sin", "sine of the heading alpha", -1.0),
    _e("cos", "cosine of the heading alpha", -1.0),
    _e("pitch", "beta / beta_max", -1.0),
    _e("endurance", "remaining endurance 1 - t / T"),
    _e("usable", "remaining usable time 1 - t / (0.85 T), clipped", -1.0),
    _e("to_landing_x", "x of (landing field - position) / operating-area diagonal", -1.0),
    _e("to_landing_y", "y of (landing field - position) / operating-area diagonal", -1.0),
    _e("neighbours", "UAVs within communication range / (N - 1)"),
    _e("flying", "1 while the UAV flies, 0 after landing or a crash"),
    _e("time", "step / horizon"),
)

#: Compass parameters: map-frame sectors (east first, counter-clockwise), ring edges (m), the
#: radius within which other UAVs are counted (m), the size of the agent-index one-hot.
N_SECTORS = 8
RING_EDGES_M = (10e3, 30e3, 70e3)
N_RINGS = len(RING_EDGES_M) + 1
OTHERS_RADIUS_M = 30e3
N_IDS = 8


def _rings_text() -> str:
    km = [0.0, *(e / 1e3 for e in RING_EDGES_M)]
    return ", ".join(f"{a:g}-{b:g}" for a, b in itertools.pairwise(km)) + f", > {km[-1]:g} km"


class Block(NamedTuple):
    """A block of consecutive values of the compass observation."""

    name: str
    size: int
    low: float | None  # None: the vector's own bounds
    high: float | None
    meaning: str


#: The ``compass`` observation (``Box((FEATURES,))`` per UAV), block by block.
COMPASS = (
    Block("vector", len(VECTOR), None, None, "the state vector (table above)"),
    Block(
        "compass",
        N_SECTORS * N_RINGS,
        0.0,
        1.0,
        f"share of the remaining POC (raster channel poc) in each of {N_SECTORS} map-frame "
        f"sectors (east first, counter-clockwise) x {N_RINGS} distance rings around the UAV "
        f"({_rings_text()}), index offset + {N_RINGS} * sector + ring",
    ),
    Block(
        "others",
        N_SECTORS,
        0.0,
        1.0,
        f"other UAVs (raster channel others) within {OTHERS_RADIUS_M / 1e3:g} km in each sector "
        "/ (N - 1), at most 1",
    ),
    Block("mean_poc", 1, 0.0, 1.0, "mean of raster channel poc (remaining POC / prior's peak)"),
    Block("index", N_IDS, 0.0, 1.0, f"the UAV's index k as a one-hot of k mod {N_IDS}"),
)


def names(table: Sequence[Entry | Block | SetBlock | RewardTerm]) -> tuple[str, ...]:
    """The names of a table's rows, in order."""
    return tuple(row.name for row in table)


def bounds(table: Sequence[Entry]) -> tuple[np.ndarray, np.ndarray]:
    """float32 (low, high) of a table of scalar entries."""
    low = np.array([e.low for e in table], dtype=np.float32)
    high = np.array([e.high for e in table], dtype=np.float32)
    return low, high


def compass_bounds() -> tuple[np.ndarray, np.ndarray]:
    """float32 (low, high) of the compass observation, block by block."""
    vlow, vhigh = bounds(VECTOR)
    lows, highs = [], []
    for b in COMPASS:
        lows.append(vlow if b.low is None else np.full(b.size, b.low, np.float32))
        highs.append(vhigh if b.high is None else np.full(b.size, b.high, np.float32))
    return np.concatenate(lows), np.concatenate(highs)


def compass_offsets() -> dict[str, slice]:
    """Each compass block's slice of the observation."""
    out, k = {}, 0
    for b in COMPASS:
        out[b.name] = slice(k, k + b.size)
        k += b.size
    return out


COMPASS_SIZE = sum(b.size for b in COMPASS)

#: The ``set`` observation's neighbour set: the K nearest other flying UAVs, one row each.
K_NEIGHBOURS = 8
#: The values of one neighbour row, in order: (name, low, high, meaning).
NEIGHBOUR_FIELDS = (
    ("dx", -2.0, 2.0, "x of (its position - own position) / operating-area diagonal"),
    ("dy", -2.0, 2.0, "y of the same"),
    ("dvx", -2.0, 2.0, "x of (its ground velocity - own) / v_max"),
    ("dvy", -2.0, 2.0, "y of the same"),
    ("dist", 0.0, 2.0, "horizontal distance / operating-area diagonal"),
    ("linked", 0.0, 1.0, "1 within communication range (eq. 24's in-range graph)"),
    ("mask", 0.0, 1.0, "1 for a real neighbour, 0 for a padding row (all its values 0)"),
)
NEIGHBOUR_SIZE = len(NEIGHBOUR_FIELDS)


class SetBlock(NamedTuple):
    """A block of consecutive values of the set observation: bounds per value (None: the
    compass observation's own)."""

    name: str
    size: int
    low: float | None
    high: float | None
    meaning: str


#: The ``set`` observation (``Box((SET_SIZE,))`` per UAV, the same size for any fleet): the
#: compass blocks without the index one-hot, a size-free symmetry breaker and fleet cue, then
#: the neighbour set, ``K_NEIGHBOURS`` rows of :data:`NEIGHBOUR_FIELDS` (nearest first, ties
#: by UAV index; padding rows are zero with ``mask`` 0), for a permutation-invariant encoder.
SET_BLOCKS = (
    *(SetBlock(b.name, b.size, None, None, b.meaning) for b in COMPASS if b.name != "index"),
    SetBlock(
        "role",
        1,
        0.0,
        1.0,
        "(j + 0.5) / n_a: the UAV's rank j among the n_a UAVs taking off from its airfield "
        "(fleet order); breaks the symmetry of UAVs that start at one point, for any fleet size",
    ),
    SetBlock(
        "centroid",
        2,
        -2.0,
        2.0,
        "x, y of (centroid of the other flying UAVs - own position) / operating-area diagonal "
        "(0 when none flies)",
    ),
    SetBlock(
        "fleet",
        2,
        0.0,
        1.0,
        "1 - 1 / N (the fleet size, bounded for any N), then flying UAVs / N",
    ),
    SetBlock(
        "neighbours",
        K_NEIGHBOURS * NEIGHBOUR_SIZE,
        None,
        None,
        f"the {K_NEIGHBOURS} nearest other flying UAVs, a row of {NEIGHBOUR_SIZE} each "
        "(neighbour table below), nearest first; missing neighbours are zero rows",
    ),
)
SET_SIZE = sum(b.size for b in SET_BLOCKS)
#: The ego part of the set observation (everything before the neighbour rows).
SET_EGO_SIZE = SET_SIZE - K_NEIGHBOURS * NEIGHBOUR_SIZE


def set_offsets() -> dict[str, slice]:
    """Each set-observation block's slice."""
    out, k = {}, 0
    for b in SET_BLOCKS:
        out[b.name] = slice(k, k + b.size)
        k += b.size
    return out


def set_bounds() -> tuple[np.ndarray, np.ndarray]:
    """float32 (low, high) of the set observation, block by block."""
    clow, chigh = compass_bounds()
    coff = compass_offsets()
    nlow = np.tile(np.array([f[1] for f in NEIGHBOUR_FIELDS], np.float32), K_NEIGHBOURS)
    nhigh = np.tile(np.array([f[2] for f in NEIGHBOUR_FIELDS], np.float32), K_NEIGHBOURS)
    lows, highs = [], []
    for b in SET_BLOCKS:
        if b.name == "neighbours":
            lows.append(nlow)
            highs.append(nhigh)
        elif b.low is None:
            lows.append(clow[coff[b.name]])
            highs.append(chigh[coff[b.name]])
        else:
            lows.append(np.full(b.size, b.low, np.float32))
            highs.append(np.full(b.size, b.high, np.float32))
    return np.concatenate(lows), np.concatenate(highs)


# -- rewards -------------------------------------------------------------------------------
class RewardTerm(NamedTuple):
    name: str
    formula: str
    meaning: str


#: The reward's terms, each with the sign it enters the reward with (:mod:`poc_env.sim.rewards`).
REWARD_TERMS = (
    RewardTerm(
        "pos",
        "+alpha * POS",
        "POS found this step (eq. 12): the swarm's (credit: team) or the UAV's own "
        "(credit: individual)",
    ),
    RewardTerm(
        "time",
        "-beta * dt / (0.85 T) / N",
        "the eq. 25 time term of the flying UAVs (team: their mean share; individual: own)",
    ),
    RewardTerm(
        "violation",
        "-violation_penalty",
        "a step with any safety or communication violation (eq. 20-24)",
    ),
    RewardTerm("overtime", "-overtime_penalty", "a step beyond the usable 0.85 T (eq. 18)"),
    RewardTerm("crash", "-crash_penalty", "once, when the UAV crashes"),
)

# -- infos ---------------------------------------------------------------------------------
#: Constraint flags, info keys ``violation_<flag>``.
VIOLATION_FLAGS = (
    ("out_of_bounds", "left the operating area (eq. 20)"),
    ("no_fly", "entered a no-fly zone (eq. 20)"),
    ("collision", "closer than the safe distance to another UAV (eq. 21)"),
    ("threat", "terrain threat above the threshold (eq. 22-23)"),
    ("comms", "out of communication with the swarm (eq. 24)"),
    ("overtime", "flying beyond the usable 0.85 T (eq. 18)"),
)


def _i(name, dtype, meaning, shape="()") -> Entry:
    return Entry(name, shape, dtype, None, None, meaning)


#: Per-agent infos of the PettingZoo env (``infos[agent]``), in order; ``reward_<term>`` and
#: ``violation_<flag>`` stand for one key per :data:`REWARD_TERMS` / :data:`VIOLATION_FLAGS` row.
INFOS = (
    _i("pos", "float", "POS found this step by the UAV (eq. 12)"),
    _i("pos_team", "float", "POS found this step by the swarm"),
    _i("posc", "float", "POSC so far (eq. 13)"),
    _i("reward_<term>", "float", "each reward term, with its sign (reward terms table)"),
    _i("violation_<flag>", "bool", "each constraint flag in this step (violation flags table)"),
    _i("shielded", "bool", "the safety shield changed this UAV's action"),
    _i("landed", "bool", "the UAV has landed"),
    _i("crashed", "bool", "the UAV has crashed"),
    _i("flight_time_s", "float", "the UAV's flight time"),
    _i("target_detected", "bool", "the hidden target was detected"),
    _i(
        "time_to_detection_s",
        "float",
        "time of that detection, -1.0 before it (not NaN: checkers compare infos with ==)",
    ),
    _i("topology", "int", "active Table 2 topology code, -1 for the auto rule"),
    _i("links", "bool", "this UAV's row of the active adjacency", shape="(N,)"),
    _i("connected", "bool", "the flying UAVs are connected through relays"),
    _i("violations", "int", "the UAV's constraint-violation steps so far (eq. 18, 20-24)"),
)


#: Infos of the moving-target tasks only (a static target's episodes keep their info set):
#: after :data:`INFOS`, in this order.
MOTION_INFOS = (
    _i(
        "mass_out",
        "float",
        "belief mass that drifted out of the map so far (POC + POSC + mass_out = 1)",
    ),
)


def info_keys() -> tuple[str, ...]:
    """Every per-agent info key, in order (the templates of :data:`INFOS` expanded)."""
    out: list[str] = []
    for e in INFOS:
        if e.name == "reward_<term>":
            out += [f"reward_{t.name}" for t in REWARD_TERMS]
        elif e.name == "violation_<flag>":
            out += [f"violation_{f}" for f, _ in VIOLATION_FLAGS]
        else:
            out.append(e.name)
    return tuple(out)


# -- tasks ---------------------------------------------------------------------------------
class Part(NamedTuple):
    """One value of a task-id part: its text in the id, what it sets, what it means."""

    text: str
    value: str | bool
    meaning: str


#: Scenario parts: id text -> built-in scenario (its size and fleet are read from the file).
SCENARIO_PARTS = (
    Part("Small", "small", "a 2-Gaussian prior (quick)"),
    Part("Paper62", "paper_6_2", "the paper's section 6.2 case (2 airfields)"),
    Part("Paper61", "paper_6_1", "the paper's section 6.1 case (fitted prior)"),
)
RANDOM_PARTS = (
    Part(
        "",
        False,
        "the scenario's prior at every reset (the seed moves the hidden target, detection "
        "thresholds and link failures only)",
    ),
    Part(
        "Random",
        True,
        "a fresh seeded Gaussian-mixture prior at every reset (random_prior=True): held-out "
        "maps for generalisation",
    ),
)
#: Motion parts: how the target moves (``target:`` section of the scenario,
#: :mod:`poc_env.theory.motion`); the value is the task's scenario overrides' name in
#: :data:`MOTION_OVERRIDES`.
MOTION_PARTS = (
    Part("", "static", "the paper's target, standing still"),
    Part(
        "Drift",
        "drift",
        "a drifting target: a uniform current of U(0, 25) km/h in a uniform direction drawn "
        "at each reset, plus diffusion D = 50 m^2/s; the belief is a Bayesian filter (predict by "
        "the motion model, update by eq. 14); info mass_out",
    ),
)
#: The scenario keyword overrides (``target__model=...``) of each motion part's value.
MOTION_OVERRIDES: dict[str, dict[str, object]] = {
    "static": {},
    "drift": {
        "target__model": "drift",
        "target__random_current_kmh": 25.0,
        "target__diffusion_m2_s": 50.0,
    },
}
#: The control levels registered with each moving-target part (the static part has all).
MOTION_CONTROLS = {"drift": ("Heading",)}
CONTROL_PARTS = (
    Part("Increments", "increments", "the paper's eq. 19 increments, Box(-1, 1, (3,)) per UAV"),
    Part("Heading", "heading", "a map-frame heading flown by the autopilot, Box(-1, 1, (2,))"),
    Part("Waypoint", "waypoint", "a target point in the operating area, Box(-1, 1, (2,))"),
)

#: Observation parts: what each UAV observes. Absent: the compass observation every task had
#: from the first release; ``Set``: the set observation, for any fleet size.
OBS_PARTS = (
    Part("", "compass", "the compass observation (its table below; index one-hot of k mod 8)"),
    Part(
        "Set",
        "set",
        "the set observation (its table below): no index width, the K nearest UAVs as a padded "
        "set; one policy for any fleet size",
    ),
)
#: The control parts each observation part other than the compass is registered with, and the
#: first version of each (it is registered at that version and every later one).
OBS_CONTROLS = {"set": {"Heading": 1, "Increments": 0}}
#: The fleet-size tasks: one scenario flown by several fleet sizes (set observation, random
#: prior, :data:`OBS_CONTROLS`' control parts): ``UAVSearch-Wide-N12-Random-Set-Heading-v1``.
SIZE_SCENARIO = Part("Wide", "wide_400", "a large area with 3 airfields for the fleet sizes")
#: The scenario's airfields, in file order: a fleet of n UAVs is spread over them round-robin
#: (:meth:`poc_env.config.Scenario.with_uavs`; ``tests/envs/test_tasks.py`` checks the names).
SIZE_AIRFIELDS = ("A", "B", "C")
SIZE_PARTS = tuple(
    Part(f"N{n}", str(n), f"{n} UAVs spread over the airfields round-robin") for n in (3, 6, 12, 24)
)


def fleet_of(n: int, airfields: Sequence[str] = SIZE_AIRFIELDS) -> list[dict[str, object]]:
    """The ``fleet`` override of ``n`` UAVs over ``airfields`` round-robin (as
    :meth:`poc_env.config.Scenario.with_uavs` spreads them)."""
    counts = [0] * len(airfields)
    for i in range(n):
        counts[i % len(airfields)] += 1
    return [{"takeoff": a, "count": c} for a, c in zip(airfields, counts, strict=True) if c]


class TaskVersion(NamedTuple):
    """One registered version of the tasks of a control part: every scenario and prior part is
    registered at each version of its control part (the old versions stay registered)."""

    #: The :data:`CONTROL_PARTS` text it versions (``"Heading"``).
    control: str
    version: int
    #: The env's ``control`` argument at this version: the level itself, or a variant of it
    #: (:data:`poc_env.sim.control.VARIANTS`) with the changed rule.
    env_control: str
    #: What changed at this version (the version history of the task table).
    change: str
    #: The recorded episode's actions (:mod:`poc_env.recorded`) are drawn this much wider than
    #: the Box, so the recording pins a rule that acts outside it.
    recorded_scale: float = 1.0


#: Every registered version of every control part, oldest first: the version history.
TASK_VERSIONS = (
    TaskVersion("Increments", 0, "increments", "first release"),
    TaskVersion("Heading", 0, "heading", "first release; an action outside the Box is "
                "normalised as it is, so a component of 1e308 flies due east"),
    TaskVersion("Heading", 1, "heading_clip", "each action component is clipped to [-1, 1] "
                "before the direction is normalised, as the other levels clip", 3.0),
    TaskVersion("Waypoint", 0, "waypoint", "first release"),
)  # fmt: skip


def versions_of(control: str) -> tuple[TaskVersion, ...]:
    """The rows of :data:`TASK_VERSIONS` of the control part ``control`` (``"Heading"``)."""
    return tuple(v for v in TASK_VERSIONS if v.control == control)


def obs_versions(obs: str) -> tuple[TaskVersion, ...]:
    """The rows of :data:`TASK_VERSIONS` the observation part value ``obs`` (``"set"``) is
    registered at (:data:`OBS_CONTROLS`)."""
    first = OBS_CONTROLS.get(obs, {})
    return tuple(v for v in TASK_VERSIONS if v.control in first and v.version >= first[v.control])


# -- markdown ------------------------------------------------------------------------------
def _table(header: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def _num(x: float | None) -> str:
    return "" if x is None else f"{x:g}"


def _bounds_text(low: float | None, high: float | None) -> str:
    return f"[{_num(low)}, {_num(high)}]"


def _scenario_text(scenario: str) -> str:
    from poc_env.config import load_scenario

    sc = load_scenario(scenario)
    m = sc.map
    w, h, c = (round(v / 1e3, 3) for v in (m.width_m, m.height_m, m.cell_m))
    ny, nx = round(m.height_m / m.cell_m), round(m.width_m / m.cell_m)
    return f"`{scenario}`: {sc.n_uavs} UAVs, {w:g} x {h:g} km ({nx} x {ny} cells of {c:g} km)"


def task_parts_markdown() -> str:
    rows = []
    for p in SCENARIO_PARTS:
        rows.append(("Scenario", f"`{p.text}`", f"{_scenario_text(str(p.value))}, {p.meaning}"))
    for p in RANDOM_PARTS:
        rows.append(("Random", f"`{p.text}`" if p.text else "(absent)", p.meaning))
    for p in CONTROL_PARTS:
        shown = ", ".join(f"`v{v.version}`" for v in versions_of(p.text))
        rows.append(("Control", f"`{p.text}`", f"`{p.value}`: {p.meaning}; versions {shown}"))
    for p in MOTION_PARTS:
        ctl = MOTION_CONTROLS.get(str(p.value))
        only = f" (with {', '.join(ctl)} only, fixed prior)" if ctl else ""
        rows.append(("Motion", f"`{p.text}`" if p.text else "(absent)", p.meaning + only))
    for p in OBS_PARTS:
        first = OBS_CONTROLS.get(str(p.value), {})
        only = ""
        if first:
            only = " (with " + ", ".join(f"{c} from v{v}" for c, v in first.items()) + " only)"
        rows.append(("Observation", f"`{p.text}`" if p.text else "(absent)", p.meaning + only))
    sizes = ", ".join(f"`{p.text}`" for p in SIZE_PARTS)
    rows.append(
        ("Size", sizes, f"with `{SIZE_SCENARIO.text}` ({_scenario_text(str(SIZE_SCENARIO.value))}"
         f", {SIZE_SCENARIO.meaning}): the fleet size; random prior and `Set` only")
    )  # fmt: skip
    moving = sum(
        len(versions_of(c)) for p in MOTION_PARTS if p.text for c in MOTION_CONTROLS[str(p.value)]
    )
    n = len(SCENARIO_PARTS) * (len(RANDOM_PARTS) * len(TASK_VERSIONS) + moving)
    for p in OBS_PARTS[1:]:
        n += len(obs_versions(str(p.value))) * (
            len(SCENARIO_PARTS) * len(RANDOM_PARTS) + len(SIZE_PARTS)
        )
    head = (
        f"Ids: `poc_env/UAVSearch-<Scenario>[-<Size>][-Random][-<Motion>][-<Observation>]-"
        f"<Control>-v<version>` ({n} tasks: every scenario and prior at every version of its "
        "control part, `poc_env.spec.TASK_VERSIONS`; moving targets with the fixed prior and "
        "the control levels listed; the set observation on every scenario and prior, and on "
        f"`{SIZE_SCENARIO.text}` at each size with the random prior, at the control parts and "
        "versions listed).\n\n"
    )
    history = _table(
        ("control", "version", "env control", "what changed"),
        [(f"`{v.control}`", f"`v{v.version}`", f"`{v.env_control}`", v.change)
         for v in TASK_VERSIONS],
    )  # fmt: skip
    return (
        head + _table(("part", "values", "meaning"), rows) + "\n\nVersion history (each old "
        "version stays registered with its behaviour):\n\n" + history
    )


def raster_markdown() -> str:
    rows = [
        (c, f"`{e.name}`", e.meaning, _bounds_text(e.low, e.high)) for c, e in enumerate(RASTER)
    ]
    return _table(("channel", "name", "meaning", "bounds"), rows)


def vector_markdown() -> str:
    rows = [
        (i, f"`{e.name}`", e.meaning, _bounds_text(e.low, e.high)) for i, e in enumerate(VECTOR)
    ]
    return _table(("index", "name", "meaning", "bounds"), rows)


def compass_markdown() -> str:
    rows = []
    for b in COMPASS:
        s = compass_offsets()[b.name]
        idx = f"{s.start}" if b.size == 1 else f"{s.start}-{s.stop - 1}"
        bnd = "the vector's" if b.low is None else _bounds_text(b.low, b.high)
        rows.append((idx, f"`{b.name}`", b.meaning, bnd))
    head = f"`Box(({COMPASS_SIZE},), float32)` per UAV, the same size on every map.\n\n"
    return head + _table(("index", "block", "meaning", "bounds"), rows)


def set_markdown() -> str:
    rows = []
    for b in SET_BLOCKS:
        s = set_offsets()[b.name]
        idx = f"{s.start}" if b.size == 1 else f"{s.start}-{s.stop - 1}"
        bnd = "the compass's" if b.low is None else _bounds_text(b.low, b.high)
        if b.name == "neighbours":
            bnd = "per field"
        rows.append((idx, f"`{b.name}`", b.meaning, bnd))
    head = (
        f"`Box(({SET_SIZE},), float32)` per UAV, the same size on every map and for every "
        f"fleet size: {SET_EGO_SIZE} ego values, then {K_NEIGHBOURS} neighbour rows of "
        f"{NEIGHBOUR_SIZE} (`poc_env.spec.K_NEIGHBOURS`).\n\n"
    )
    fields = _table(
        ("field", "meaning", "bounds"),
        [(f"`{n}`", m, _bounds_text(lo, hi)) for n, lo, hi, m in NEIGHBOUR_FIELDS],
    )
    return (
        head
        + _table(("index", "block", "meaning", "bounds"), rows)
        + f"\n\nNeighbour row (row r at offset {set_offsets()['neighbours'].start} + "
        f"{NEIGHBOUR_SIZE} r):\n\n" + fields
    )


def reward_markdown() -> str:
    rows = [(f"`{t.name}`", f"`reward_{t.name}`", t.formula, t.meaning) for t in REWARD_TERMS]
    return _table(("term", "info key", "enters as", "per step and agent"), rows)


def info_markdown() -> str:
    rows = [(f"`{e.name}`", e.dtype, e.shape, e.meaning) for e in INFOS]
    rows += [(f"`{e.name}`", e.dtype, e.shape, f"moving targets only: {e.meaning}")
             for e in MOTION_INFOS]  # fmt: skip
    flags = _table(("flag", "meaning"), [(f"`{f}`", m) for f, m in VIOLATION_FLAGS])
    return (
        _table(("key", "type", "shape", "meaning"), rows)
        + f"\n\nViolation flags (`violation_<flag>`):\n\n{flags}"
    )


#: The generated sections of ``docs/environment.md``, by marker name.
SECTIONS = {
    "tasks": task_parts_markdown,
    "raster": raster_markdown,
    "vector": vector_markdown,
    "compass": compass_markdown,
    "set": set_markdown,
    "rewards": reward_markdown,
    "infos": info_markdown,
}
DOC = Path(__file__).resolve().parents[1] / "docs" / "environment.md"


def markdown(name: str) -> str:
    """The generated markdown of section ``name`` (:data:`SECTIONS`)."""
    return SECTIONS[name]()


def render_doc(text: str) -> str:
    """``text`` with every ``<!-- spec:NAME -->`` ... ``<!-- /spec:NAME -->`` section replaced
    by its generated markdown (KeyError for an unknown or missing section)."""
    for name in SECTIONS:
        pattern = re.compile(rf"(<!-- spec:{name} -->\n).*?(<!-- /spec:{name} -->)", re.DOTALL)
        m = pattern.search(text)
        if m is None:
            raise KeyError(f"docs section <!-- spec:{name} --> missing")
        text = text[: m.end(1)] + markdown(name) + "\n" + text[m.start(2) :]
    return text


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of ``poc-env spec``."""
    p.add_argument("--write", action="store_true", help="rewrite the page's generated sections")
    p.add_argument("--doc", default=str(DOC), help="the page")


def main_args(args: argparse.Namespace) -> int:
    """Check (exit status 1 if stale) or, with ``--write``, rewrite the generated sections of
    ``docs/environment.md``."""
    from poc_env.errors import ConfigError
    from poc_env.io import read_text, write_text_atomic

    path = Path(args.doc)
    page = "docs/environment.md of a source checkout, or a page with its spec markers"
    old = read_text(path, "doc", f"a readable page ({page})")
    try:
        new = render_doc(old)
    except KeyError as err:  # a page without the generated sections' markers
        raise ConfigError("doc", str(path), f"a page with every section's markers "
                          f"({err.args[0]})") from None  # fmt: skip
    if args.write:
        if new != old:
            write_text_atomic(path, new)
        print(f"{path}: {'rewritten' if new != old else 'up to date'}")
        return 0
    if new != old:
        print(f"{path} is stale: run poc-env spec --write", file=sys.stderr)
        return 1
    print(f"{path}: up to date")
    return 0
