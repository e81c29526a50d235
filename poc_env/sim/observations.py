"""Per-agent observations and the global state, batched over envs and agents.

The layouts (raster channels, vector entries, compass blocks: names, bounds, meanings) are the
tables of :mod:`poc_env.spec` (``RASTER``, ``VECTOR``, ``COMPASS``), rendered in
``docs/environment.md``; this module reads its names, sizes and bounds from there.
"""

from __future__ import annotations

import functools

import numpy as np

import poc_env._kernels.observations as _kernels
import poc_env.spec as spec
from poc_env.sim import constraints as cons
from poc_env.sim.comms import _shaped
from poc_env.sim.core import Params, State

#: Raster channels in order (:data:`poc_env.spec.RASTER`); by name: ``RASTER_INDEX["poc"]``.
RASTER_NAMES = spec.names(spec.RASTER)
RASTER_INDEX = {name: c for c, name in enumerate(RASTER_NAMES)}
RASTER_CHANNELS = len(RASTER_NAMES)
#: State-vector entries in order (:data:`poc_env.spec.VECTOR`).
VECTOR_NAMES = spec.names(spec.VECTOR)
VECTOR_SIZE = len(VECTOR_NAMES)
#: Vector entries by name: ``vec[..., VECTOR_INDEX["flying"]]``.
VECTOR_INDEX = {name: i for i, name in enumerate(VECTOR_NAMES)}
VECTOR_LOW, VECTOR_HIGH = spec.bounds(spec.VECTOR)


def split_observation(obs, grid_shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """(raster (RASTER_CHANNELS, ny, nx), vector (VECTOR_SIZE,)) of one agent's observation.

    ``obs`` is a ``dict`` observation (``obs_type="dict"``) or a flat one (``obs_type="flat"``:
    the raster raveled in C order, then the vector); ``grid_shape`` is ``(ny, nx)``. The arrays
    are views where possible.
    """
    if isinstance(obs, dict):
        return np.asarray(obs["raster"]), np.asarray(obs["vector"])
    flat = np.asarray(obs)
    ny, nx = grid_shape
    if flat.shape != (RASTER_CHANNELS * ny * nx + VECTOR_SIZE,):
        raise ValueError(
            f"flat observation of shape {flat.shape} does not match a {ny} x {nx} grid "
            f"({RASTER_CHANNELS * ny * nx + VECTOR_SIZE} values expected)"
        )
    return flat[:-VECTOR_SIZE].reshape(RASTER_CHANNELS, ny, nx), flat[-VECTOR_SIZE:]


def hazard_mask(params: Params) -> np.ndarray:
    """(ny, nx) float32: 1 where a cell centre is in a no-fly zone or above the threat limit."""
    c = params.grid.centers
    mask = np.zeros(params.grid.shape, dtype=bool)
    if len(params.zones):
        mask |= params.zones.inside(c)
    if len(params.threat_lambdas):
        mask |= cons.threat_violation(
            c, params.threat_centers, params.threat_lambdas, params.scenario.map.threat_threshold
        )
    return mask.astype(np.float32)


def cell_pixels(params: Params, xy: np.ndarray):
    """Row, column and inside-grid mask of positions (..., 2)."""
    g = params.grid
    inside = g.contains(xy)
    j, i = g.cell_of(xy)
    return j, i, inside


def rasters(
    params: Params,
    state: State,
    poc_scale: np.ndarray,
    hazard: np.ndarray,
    out: np.ndarray | None = None,
):
    """(E, N, C, ny, nx) float32 raster observations of every agent (``hazard`` is (ny, nx)),
    written into ``out`` when given (a view of the flat observation)."""
    e, n = state.flying.shape
    g = params.grid
    s = params.s
    if out is None:
        out = np.empty((e, n, RASTER_CHANNELS, g.ny, g.nx), dtype=np.float32)
    x0, y0, x1, y1 = g.bounds
    # the kernel sums sub-cells in numpy's order for rows of s < 8 points over several columns;
    # otherwise numpy's own sum (Grid.coarsen) is passed in
    own_sum = g.nx > 1 and s < 8
    coarse = _NO_COARSE if own_sum else g.coarsen(state.belief, s)
    _kernels.rasters(
        state.belief,
        s,
        coarse,
        own_sum,
        np.asarray(poc_scale, dtype=float),
        _shaped(hazard, (g.ny, g.nx), np.float32),
        state.pos,
        state.flying,
        float(x0),
        float(y0),
        float(x1),
        float(y1),
        float(g.cell_m),
        out,
    )
    if state.known is not None:  # belief_sharing "comms": each UAV sees its own belief
        out[:, :, 0] = _own_poc(params, state, poc_scale)
    return out


def _own_poc(params: Params, state: State, poc_scale: np.ndarray) -> np.ndarray:
    """(E, N, ny, nx) float64: each UAV's own coarse belief / POC scale, clipped to [0, 1]
    (belief_sharing "comms")."""
    own = params.grid.coarsen(state.agent_beliefs(), params.s)
    return np.clip(own / np.asarray(poc_scale)[:, None, None, None], 0.0, 1.0)


def coarse_poc(params: Params, state: State, poc_scale: np.ndarray) -> np.ndarray:
    """(E, P, ny, nx) float32: raster channel 0 of every env, once per env (P = 1) when its
    UAVs share the belief, else (belief_sharing "comms") each UAV's own (P = N)."""
    if state.known is not None:
        return _own_poc(params, state, poc_scale).astype(np.float32)
    g = params.grid
    s = params.s
    own_sum = g.nx > 1 and s < 8  # as in :func:`rasters`
    coarse = _NO_COARSE if own_sum else g.coarsen(state.belief, s)
    out = np.empty((state.flying.shape[0], g.ny, g.nx), dtype=np.float32)
    _kernels.coarse_poc(state.belief, s, coarse, own_sum, np.asarray(poc_scale, dtype=float), out)
    return out[:, None]


_NO_COARSE = np.zeros((1, 1, 1))


def vectors(params: Params, state: State, out: np.ndarray | None = None) -> np.ndarray:
    """(E, N, VECTOR_SIZE) float32 state vectors of every agent, written into ``out`` when
    given (a view of the flat observation)."""
    n = state.flying.shape[1]
    if out is None:
        out = np.empty((*state.flying.shape, VECTOR_SIZE), dtype=np.float32)
    sin_h, cos_h = _sin_cos(state.heading)
    _kernels.vectors_of(
        state.pos,
        state.speed,
        sin_h,
        cos_h,
        state.pitch,
        state.elapsed,
        state.flying,
        state.step,
        params.landing,
        *_vector_constants(params, n),
        out,
    )
    return out


#: The headings of the last large :func:`_sin_cos` call (a copy), their sines and cosines.
_TRIG: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
#: Below this many UAVs numpy's sine and cosine cost less than comparing the headings.
_TRIG_MIN = 256


def _sin_cos(heading: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``np.sin(heading)`` and ``np.cos(heading)``; those of the last call again when its
    headings were these, bit for bit (each step computes the vectors twice: the autopilot's
    at its start, of the headings the last observation saw unless something wrote them since,
    which the comparison sees). The arrays returned are only read."""
    global _TRIG
    h = heading
    if h.size < _TRIG_MIN or h.dtype != np.float64 or not h.flags.c_contiguous:
        return np.sin(h), np.cos(h)
    last = _TRIG  # (one read: another thread may replace it, never change it)
    if (
        last is not None
        and last[0].shape == h.shape
        and np.array_equal(last[0].view(np.int64), h.view(np.int64))
    ):
        return last[1], last[2]
    sin_h, cos_h = np.sin(h), np.cos(h)
    _TRIG = (h.copy(), sin_h, cos_h)
    return sin_h, cos_h


#: The vectors kernel's arguments after the state's and the landing fields: its 14 scalars
#: (``bx0`` to ``others``) in one float64 array (``vectors_of``: numba unboxes one array
#: faster than 14 floats), then the two bound arrays.
_VectorConstants = tuple[np.ndarray, np.ndarray, np.ndarray]
#: :func:`_vector_constants` of the Params seen last, by id (each entry keeps its Params).
_VECTOR_CONSTANTS: dict[tuple[int, int], tuple[Params, _VectorConstants]] = {}


def _vector_constants(params: Params, n: int) -> _VectorConstants:
    """The vectors kernel's arguments after the state's and the landing fields for ``params``
    and ``n`` UAVs per env, formed once per Params (a step computes the vectors twice: for the
    autopilot and the observation)."""
    key = (id(params), n)
    hit = _VECTOR_CONSTANTS.get(key)
    if hit is not None and hit[0] is params:
        return hit[1]
    sc = params.scenario
    u = sc.uav
    bx0, by0, bx1, by1 = params.bounds
    w, h = bx1 - bx0, by1 - by0
    scalars = np.array(
        (
            float(bx0), float(by0), float(w), float(h), _diagonal(w, h), float(u.max_altitude_m),
            float(u.min_speed_mps), float(u.max_speed_mps - u.min_speed_mps),
            float(u.max_pitch_rad), float(u.endurance_s), float(u.usable_endurance_s),
            float(params.horizon), float(sc.comms.range_m), float(max(n - 1, 1)),
        ),
        dtype=np.float64,
    )  # fmt: skip
    k: _VectorConstants = (scalars, _LOW, _HIGH)
    if len(_VECTOR_CONSTANTS) >= 64:  # many scenarios in one process: start over
        _VECTOR_CONSTANTS.clear()
    _VECTOR_CONSTANTS[key] = (params, k)
    return k


@functools.lru_cache(maxsize=64)
def _diagonal(w: float, h: float) -> float:
    """Diagonal of the operating area (``np.hypot``), once per scenario."""
    return float(np.hypot(w, h))


_LOW = VECTOR_LOW.astype(np.float64)
_HIGH = VECTOR_HIGH.astype(np.float64)


def decode_vector(params: Params, vec: np.ndarray) -> dict[str, np.ndarray]:
    """Physical quantities back from state vectors (..., VECTOR_SIZE): the inverse of
    :func:`vectors` for position (m), altitude (m), speed (m/s), heading and pitch (rad)."""
    u = params.scenario.uav
    bx0, by0, bx1, by1 = params.bounds
    v = np.asarray(vec, dtype=float)
    i = VECTOR_INDEX
    return {
        "xy": np.stack(
            [bx0 + v[..., i["x"]] * (bx1 - bx0), by0 + v[..., i["y"]] * (by1 - by0)], -1
        ),
        "z": v[..., i["z"]] * u.max_altitude_m,
        "speed": u.min_speed_mps + v[..., i["speed"]] * (u.max_speed_mps - u.min_speed_mps),
        "heading": np.arctan2(v[..., i["sin"]], v[..., i["cos"]]),
        "pitch": v[..., i["pitch"]] * u.max_pitch_rad,
        "flying": v[..., i["flying"]] > 0.5,
        "usable": v[..., i["usable"]],
    }


# ------------------------------------------------------------------- compass observation

# the layout is :data:`poc_env.spec.COMPASS`: blocks vector, compass, others, mean_poc, index
N_SECTORS = spec.N_SECTORS
RING_EDGES_M = spec.RING_EDGES_M
N_RINGS = spec.N_RINGS
OTHERS_RADIUS_M = spec.OTHERS_RADIUS_M
N_IDS = spec.N_IDS
FEATURES = spec.COMPASS_SIZE
FEATURE_LOW, FEATURE_HIGH = spec.compass_bounds()
_BLOCK = spec.compass_offsets()


class CompassFeatures:
    """The ``compass`` observation (``obs_type="compass"``): the state vector, the belief
    compass, nearby UAVs per sector, the mean remaining POC and the agent index (the blocks of
    :data:`poc_env.spec.COMPASS`, tabulated in ``docs/environment.md``), computed from the
    raster and vector observations of any number of UAVs at once.

    ``agent_index=False`` leaves the index block at zero: the ablation of the credit-and-sharing
    table (a shared policy that cannot tell the UAVs of one airfield apart). With the index and
    more than :data:`N_IDS` UAVs, UAVs ``k`` and ``k + N_IDS`` read the same index: a
    UserWarning says so (the set observation, ``obs_type="set"``, has no index width)."""

    def __init__(self, params: Params, agent_index: bool = True) -> None:
        self.params = params
        self.agent_index = bool(agent_index)
        if self.agent_index and params.n_agents > N_IDS:
            import warnings

            warnings.warn(
                f"the compass observation of {params.n_agents} UAVs: its index block is a "
                f"one-hot of k mod {N_IDS}, so UAVs 0 and {N_IDS} (and every k, k + {N_IDS}) "
                "read the same index; a policy on it cannot tell them apart (obs_type='set', "
                "the -Set tasks, observes any fleet size)",
                UserWarning,
                stacklevel=2,
            )
        self.centers = params.grid.centers.reshape(-1, 2).astype(float)
        self._cx = np.ascontiguousarray(self.centers[:, 0])
        self._cy = np.ascontiguousarray(self.centers[:, 1])
        self._edges = np.asarray(RING_EDGES_M, dtype=float)
        self.others = max(params.n_agents - 1, 1)
        b = _BLOCK
        self._layout = (
            b["vector"].start, b["compass"].start, b["others"].start, b["mean_poc"].start,
            b["index"].start, N_IDS, N_SECTORS, self.agent_index,
        )  # fmt: skip
        g = params.grid
        bx0, by0, bx1, by1 = params.bounds
        x0, y0, x1, y1 = g.bounds
        self._grid_box = (float(x0), float(y0), float(x1), float(y1), float(g.cell_m))
        self._area = (
            float(bx0), float(by0), float(bx1 - bx0), float(by1 - by0), float(OTHERS_RADIUS_M),
            float(self.others),
        )  # fmt: skip

    def __call__(self, raster: np.ndarray, vector: np.ndarray, k) -> np.ndarray:
        """``raster (B, C, ny, nx)``, ``vector (B, VECTOR_SIZE)`` of UAVs ``k (B,)`` ->
        ``(B, FEATURES)``."""
        raster = np.asarray(raster, dtype=np.float32)
        vector = np.asarray(vector, dtype=np.float32)
        b = vector.shape[0]
        out = np.zeros((b, FEATURES), dtype=np.float32)
        out[:, _BLOCK["vector"]] = vector
        if b == 0:
            return out
        xy = decode_vector(self.params, vector)["xy"]
        poc = raster[:, RASTER_INDEX["poc"]].reshape(b, -1).astype(float)
        others = raster[:, RASTER_INDEX["others"]].reshape(b, -1).astype(float)
        mass, count = _kernels.compass_bins(
            self._cx, self._cy, np.ascontiguousarray(xy[:, 0]), np.ascontiguousarray(xy[:, 1]),
            poc, others, self._edges, float(OTHERS_RADIUS_M), N_SECTORS,
        )  # fmt: skip
        total = poc.sum(axis=1)
        share = np.divide(mass, total[:, None], out=np.zeros_like(mass), where=total[:, None] > 0)
        out[:, _BLOCK["compass"]] = share
        out[:, _BLOCK["others"]] = np.minimum(count / self.others, 1.0)
        out[:, _BLOCK["mean_poc"]] = poc.mean(axis=1)[:, None]
        if self.agent_index:
            out[np.arange(b), _BLOCK["index"].start + np.asarray(k) % N_IDS] = 1.0
        return out

    def of_state(
        self, state: State, poc_scale: np.ndarray, out: np.ndarray | None = None
    ) -> np.ndarray:
        """``(E, N, FEATURES)``: every agent's features of ``state`` (POC scales ``poc_scale
        (E,)``), equal to calling the instance on the raster and vector observations, but
        computed from each env's coarse POC and the UAVs' positions without the rasters.
        ``out (E, N, F >= FEATURES)``: written in place (zeroed, then the compass blocks at
        their offsets; the set observation's blocks follow them)."""
        params = self.params
        vec = vectors(params, state)
        poc = coarse_poc(params, state, poc_scale)
        e, n = state.flying.shape
        if out is None:
            out = np.empty((e, n, FEATURES), dtype=np.float32)
        _kernels.compass(
            poc,
            vec,
            state.pos,
            state.flying,
            self._grid_box,
            self._area,
            self._cx,
            self._cy,
            self._edges,
            self._layout,
            out,
        )  # fmt: skip
        return out


# ----------------------------------------------------------------------- set observation

SET_SIZE = spec.SET_SIZE
SET_LOW, SET_HIGH = spec.set_bounds()
_SET_BLOCK = spec.set_offsets()
K_NEIGHBOURS = spec.K_NEIGHBOURS


def roles(params: Params) -> np.ndarray:
    """(N,) float: each UAV's ``role`` cue, ``(j + 0.5) / n_a`` for the UAV ranked ``j`` (fleet
    order) among the ``n_a`` UAVs taking off from its airfield (:data:`poc_env.spec.SET_BLOCKS`)."""
    fields = [g.takeoff for g in params.scenario.fleet for _ in range(g.count)]
    out = np.empty(len(fields))
    for k, name in enumerate(fields):
        out[k] = (fields[:k].count(name) + 0.5) / fields.count(name)
    return out


class SetFeatures:
    """The ``set`` observation (``obs_type="set"``; :data:`poc_env.spec.SET_BLOCKS`): the
    compass blocks without the index one-hot (:class:`CompassFeatures` writes them), a role
    cue, the offset to the other UAVs' centroid and the fleet size, then the
    :data:`K_NEIGHBOURS` nearest other flying UAVs as padded rows with a mask. Nothing in it
    depends on a fixed fleet width, so one policy reads any number of UAVs."""

    def __init__(self, params: Params) -> None:
        self.params = params
        self.compass = CompassFeatures(params, agent_index=False)
        self.role = roles(params)
        u = params.scenario.uav
        bx0, by0, bx1, by1 = params.bounds
        self._scales = (
            _diagonal(bx1 - bx0, by1 - by0),
            float(u.max_speed_mps),
            float(params.scenario.comms.range_m),
        )
        b = _SET_BLOCK
        self._layout = (
            b["role"].start, b["centroid"].start, b["fleet"].start, b["neighbours"].start,
            K_NEIGHBOURS, spec.NEIGHBOUR_SIZE,
        )  # fmt: skip
        assert all(_SET_BLOCK[k] == _BLOCK[k] for k in ("vector", "compass", "others", "mean_poc"))

    def of_state(self, state: State, poc_scale: np.ndarray) -> np.ndarray:
        """``(E, N, SET_SIZE)`` float32: every agent's set observation of ``state``."""
        e, n = state.flying.shape
        out = np.empty((e, n, SET_SIZE), dtype=np.float32)
        self.compass.of_state(state, poc_scale, out)
        _kernels.swarm_set(
            state.pos, state.speed, state.heading, state.pitch, state.flying, self.role,
            self._scales, self._layout, out,
        )  # fmt: skip
        return out


#: Observation kinds of every env (``obs_type``): raster + vector, the two raveled, the compass,
#: the set.
OBS_TYPES = ("dict", "flat", "compass", "set")


def observe(
    params: Params,
    state: State,
    poc_scale: np.ndarray,
    hazard: np.ndarray,
    obs_type: str,
    features: CompassFeatures | SetFeatures | None = None,
):
    """Every agent's observation of kind ``obs_type``, batched over envs and agents: for
    ``"dict"`` a dict of ``raster (E, N, C, ny, nx)`` and ``vector (E, N, VECTOR_SIZE)``; for
    ``"flat"`` (the raster raveled in C order, then the vector), ``"compass"``
    (:class:`CompassFeatures`, pass one to reuse it) and ``"set"`` (:class:`SetFeatures`) a
    float32 array ``(E, N, D)``. The one implementation the PettingZoo env, the Gymnasium
    views and the VecEnvs share."""
    if obs_type == "dict":
        return {
            "raster": rasters(params, state, poc_scale, hazard),
            "vector": vectors(params, state),
        }
    if obs_type == "compass":
        f = features if isinstance(features, CompassFeatures) else CompassFeatures(params)
        return f.of_state(state, poc_scale)
    if obs_type == "set":
        sf = features if isinstance(features, SetFeatures) else SetFeatures(params)
        return sf.of_state(state, poc_scale)
    # flat: both written in place into one array (no concatenated copy)
    e, n = state.flying.shape
    g = params.grid
    size = RASTER_CHANNELS * g.ny * g.nx
    flat = np.empty((e, n, size + VECTOR_SIZE), dtype=np.float32)
    rasters(params, state, poc_scale, hazard, flat[:, :, :size].reshape(e, n, -1, g.ny, g.nx))
    vectors(params, state, flat[:, :, size:])
    return flat
