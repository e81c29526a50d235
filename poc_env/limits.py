"""Documented limits on inputs, and the memory guard.

Physical plausibility: a scenario outside these ranges is almost surely a typo (a speed in m/s
written under ``_kmh``, metres under ``_km``) or hostile input, and values far outside them make
numpy overflow or allocate without end. Each limit is generous against real aircraft and search
areas; raise one here if a real use needs it.

Memory: before a large allocation (a map's cells, a batch of environments, a planner
population) its size is estimated and compared with :func:`memory_limit_bytes`, 4 GiB unless the
environment variable ``POC_ENV_MAX_MEMORY_GB`` or the CLI flag ``--max-memory-gb`` says
otherwise, so that a mistyped size ends in a clear error naming the field instead of the kernel
killing the process.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator

from poc_env.errors import ConfigError, as_number

# --------------------------------------------------------------------------- physical ranges
#: Smallest value of a quantity that must be positive (a length, speed, rate, weight), in its
#: YAML unit: subnormal values such as 5e-324 pass "> 0" and then overflow a division.
MIN_POSITIVE = 1e-9
#: Largest side of the search area, and largest distance of any point (origin, airfields,
#: zones, peaks) from the map origin: 2,000 km (a continental search; the paper's is 200 km).
MAX_EXTENT_KM = 2000.0
#: Largest distance of any configured point (origin, airfields, zones, peaks) from the map
#: origin, km.
MAX_COORD_KM = 10_000.0
#: Longest airfield name and no-fly zone name (characters): what plan.json and every export
#: carry (an airfield name becomes part of labels and rally-point names).
MAX_AIRFIELD_NAME = 64
MAX_ZONE_NAME = 200
#: Smallest cell side: 10 m (a search cell narrower than any sensor footprint is meaningless).
MIN_CELL_KM = 0.01
#: Fastest UAV: 1,500 km/h (beyond any search aircraft; the paper's fly 100-240 km/h).
MAX_SPEED_KMH = 1500.0
#: Endurance from 0.01 h (36 s; a subnormal endurance made the time share of the reward infinite)
#: to 240 h (ten days; the paper's UAVs fly 3 h).
MIN_ENDURANCE_H = 0.01
MAX_ENDURANCE_H = 240.0
#: Largest acceleration (m/s^2), turn and pitch rates (deg/s), pitch (deg), altitude (m).
MAX_ACCEL_MPS2 = 100.0
MAX_RATE_DEG_S = 360.0
MAX_PITCH_DEG = 89.0
MAX_ALTITUDE_M = 30_000.0
#: Largest vertical rate, climb or sink (m/s; ``uav.max_climb_rate_mps``,
#: ``uav.max_sink_rate_mps`` and a plan's terrain record): PX4 allows at most 15.
MAX_VERTICAL_RATE_MPS = 100.0
#: Widest sensor sweep and longest comms range / separation, km.
MAX_SWEEP_WIDTH_KM = 200.0
MAX_RANGE_KM = 20_000.0
#: Longest time step: one hour; most steps per episode: 10^7.
MAX_DT_S = 3600.0
MAX_STEPS = 10_000_000
#: Most cell updates of a moving target's predict step in one env step: its sub-steps (the
#: stability rule of :func:`poc_env.theory.motion.substeps`, 4 D dt / h^2 for the diffusion)
#: times the filter's sub-cells. About 3e8 updates a second on one core: a few seconds a step.
MAX_FILTER_UPDATES = 1e9
#: Most of those sub-steps in one env step: more means the diffusion spreads over hundreds of
#: sub-cells a step, which the grid cannot resolve, and the moving-target bound of
#: ``evaluate`` (which runs the sub-steps forwards and backwards per sweep) takes minutes.
MAX_FILTER_SUBSTEPS = 1000
#: Largest reward weight or penalty (keeps sums of rewards far from float overflow).
MAX_WEIGHT = 1e9
#: Largest planner population (``planner.population``, ``plan --popsize``; the paper: 100),
#: generations (the paper: 300), and batch of environments (``train --n-envs``).
POPSIZE_MAX = 10_000
MAXITER_MAX = 100_000
N_ENVS_MAX = 1024
#: Most episodes per policy in one ``evaluate`` (the paper's tables use 10 to 50), most worker
#: processes, and the largest seed (numpy takes any; 2^53 is exact as a float in every file format).
MAX_EPISODES = 10_000
MAX_WORKERS = 256
MAX_SEED = 2**53

# --------------------------------------------------------------------------- memory guard
DEFAULT_MEMORY_GB = 4.0
_ENV_VAR = "POC_ENV_MAX_MEMORY_GB"


def set_memory_limit_gb(gb: float | None) -> None:
    """Set the memory guard's limit for this process and its workers (None: back to default)."""
    if gb is None:
        os.environ.pop(_ENV_VAR, None)
        return
    os.environ[_ENV_VAR] = repr(as_number("max_memory_gb", gb, 0.0, 1e6, lo_open=True))


@contextlib.contextmanager
def memory_limit_gb(gb: float | None) -> Iterator[None]:
    """:func:`set_memory_limit_gb` for the block (None: leave the limit as it is), then the
    limit as it was before: ``poc_env.cli.main`` called twice in one process with different
    ``--max-memory-gb`` (or the second time without it) gets each call's own limit, where the
    first call's stayed in ``os.environ`` (cli-audit). Workers started in the block inherit
    it."""
    before = os.environ.get(_ENV_VAR)
    if gb is not None:
        set_memory_limit_gb(gb)
    try:
        yield
    finally:
        if before is None:
            os.environ.pop(_ENV_VAR, None)
        else:
            os.environ[_ENV_VAR] = before


def memory_limit_bytes() -> float:
    """The guard's limit: ``POC_ENV_MAX_MEMORY_GB`` GiB (default 4)."""
    text = os.environ.get(_ENV_VAR)
    if text is None:
        return DEFAULT_MEMORY_GB * 2**30
    try:
        gb = float(text)
    except ValueError:
        raise ConfigError(_ENV_VAR, text, "a number of GiB > 0") from None
    return as_number(_ENV_VAR, gb, 0.0, 1e6, lo_open=True) * 2**30


def check_memory(field: str, value: object, nbytes: float, what: str) -> None:
    """Raise :class:`ConfigError` on ``field`` if ``what`` would need more than the limit."""
    limit = memory_limit_bytes()
    if nbytes > limit:
        raise ConfigError(
            field,
            value,
            f"a size whose {what} fits the memory limit: it needs about {_gib(nbytes)}, the "
            f"limit is {_gib(limit)} (raise it with --max-memory-gb or {_ENV_VAR})",
        )


def _gib(n: float) -> str:
    return f"{n / 2**30:.3g} GiB"


#: Bytes per map cell of the largest structure built from a map: the prior is integrated on a
#: 6 x 6 sub-grid per cell (coordinates, densities and temporaries), measured with tracemalloc
#: on 10^4 to 6.4 x 10^5 cells: 2,330 B a cell (tests/test_limits.py keeps it an upper bound).
MAP_BYTES_PER_CELL = 4096


#: Bytes per sample point of :func:`poc_env.theory.regions.reach_share`'s exact measure (the
#: zone reach of the bounds, :func:`poc_env.theory.bound.zone_reach`): coordinates, masks and
#: a shapely point per sample inside a zone. Peak RSS measured at 266-273 B a sample for 1.6 x
#: 10^5 to 5.8 x 10^6 samples, every one inside the zone (results/audit/terrainleft).
REACH_BYTES_PER_SAMPLE = 512


def map_bytes(cells: int) -> float:
    """Estimated peak bytes of building and holding a map of ``cells`` cells."""
    return float(cells) * MAP_BYTES_PER_CELL


def env_bytes(cells: int, samples_per_cell: int, n_agents: int, n_envs: int, comms: bool) -> float:
    """Estimated peak bytes of ``n_envs`` environments over a map of ``cells`` cells: the map
    (:func:`map_bytes`) plus, per env, the fine belief (``samples_per_cell``^2 points a cell,
    one copy per agent under ``belief_sharing: comms``) and its temporaries. Calibrated like
    :data:`MAP_BYTES_PER_CELL` (measured about a quarter of it: 290 B a cell and env with one
    shared belief, 2,960 with three agents' beliefs, s = 4).

    Under ``belief_sharing: comms`` each env also holds ``N x N`` fine maps of float64
    (``State.known``: UAV i's copy of UAV j's survival), and holds them twice at its peaks
    (the copy step's temporary; a reset's new state beside the old one): ``16 s^2 N^2`` bytes
    a cell more. Counting N maps only, the estimate was a third of the measured peak at 12
    UAVs and a fifth at 24 (tests/test_validation.py), so the guard passed sizes the kernel
    then killed."""
    s2 = samples_per_cell**2
    per_cell = 256 + 64 * s2 * (n_agents if comms else 1)
    if comms:
        per_cell += 16 * s2 * n_agents**2
    return map_bytes(cells) + float(n_envs) * cells * per_cell


def plan_bytes(popsize: int, n_uavs: int, cells: int) -> float:
    """Estimated peak bytes of a DE planner population: the map (:func:`map_bytes`), the
    ``(P, P)`` keys from which DE/rand/1 draws each member's three partners (float64 keys and
    their int64 partition, about 24 B per pair), and the compiled plan pass's per-member arrays
    (about 260 B per member and UAV; no ``(P, n, cells)`` array since the pass integrates the
    rectangles' boundaries). Measured with tracemalloc (scale-audit): ``small`` at popsize
    1,000 and 10,000 (24 and 2,297 MiB), ``paper_6_2`` at 1,000 and 4,000, 160 x 160 cells
    with 24 and 64 UAVs at 100 to 2,000 (32 to 124 MiB); 32 B per pair and 512 B per member
    and UAV keep it an upper bound (tests/test_validation.py). The former 48 B per member,
    UAV and cell was 86 times the peak at 24 UAVs on 160 x 160 cells and refused 64 UAVs
    there (7.4 GiB estimated, 68 MiB used), and a quarter of it at popsize 10,000."""
    return map_bytes(cells) + 32.0 * float(popsize) ** 2 + 512.0 * popsize * n_uavs
