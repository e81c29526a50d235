"""The table of target motion models: how a lost target, and the belief about it, move.

The paper's target stands still (``static``). A moving target turns the belief into a Bayesian
filter: every step first *predicts* (the model moves the fine belief) and then *updates* by
eq. 14 (the sensors' sweep). Every moving model here is advection by a velocity field ``v``
plus isotropic diffusion of coefficient ``D`` (m^2/s), the Fokker-Planck equation of the
target's random walk ``dx = v dt + sqrt(2 D) dW``:

    d p / d t = - div(v p) + D laplacian(p)

Models (:data:`MODELS`; ``target.model`` of the scenario, :class:`~poc_env.config.TargetConfig`):

``static``
    The paper: ``v = 0, D = 0``; the environment skips the predict step entirely.
``diffusion``
    ``v = 0``: a mass-conserving random walk; the variance of a blob grows by ``2 D t`` per
    axis.
``drift``
    ``v`` = the current: ``current_kmh`` (uniform), plus a uniform current of random speed and
    direction drawn at each reset (``random_current_kmh``), plus an optional gridded,
    time-varying field (``field_file``, :class:`VelocityField`); plus diffusion ``D``.
``leeway``
    ``v`` = the current plus the leeway of the target class in the 10 m wind ``W``
    (``wind_kmh``): downwind ``a_d |W| + b_d`` along the wind, crosswind ``a_c |W| + b_c`` to
    its right or left (the side drawn once per episode, 50/50); plus diffusion ``D``. The
    classes are :data:`LEEWAY_CLASSES`. The wind may be gridded and time-varying
    (``wind_file``, read as the current is; the leeway is then that of each cell's wind at
    each time, the side still one per episode), and the current may be a gridded field too.

Numerics (:func:`advect_diffuse`): a finite-volume step on the fine grid, first-order upwind
fluxes for advection and centred fluxes for diffusion, explicit, sub-stepped so that
``(|u| + |v|) tau / h + 4 D tau / h^2 <= 1`` (every cell's outflow at most its mass: positive
and stable). The scheme is conservative by construction: every flux leaves one cell and
enters its neighbour; fluxes through the map's edge (outside the map holds no belief, the
boundary absorbs) are summed into ``mass_out``, so ``in-map + out-of-map`` mass is conserved to
rounding. For a uniform velocity the centre of mass of the interior moves by exactly ``v t``
and the diffusion adds exactly ``2 D t`` of variance per axis; upwinding adds the numerical
diffusion ``|u| h / 2 (1 - |u| tau / h)`` along the flow.

The hidden target moves by the same law (:func:`move_targets`): ``x += v(x, t) dt +
sqrt(2 D dt) xi`` with ``xi`` standard normal, from noise drawn at reset from a stream of its
own (``rng.spawn``), so the env's generator draws nothing more for it. A target that leaves the
map stays out and can no longer be detected, as the belief's mass that left it.

Adding a model: one :class:`MotionModel` entry here (its per-episode velocity draw) and its
tests (``tests/theory/test_motion.py``).
"""

from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import poc_env._kernels.motion as _kernel
from poc_env.config import LEEWAY_CLASS_NAMES, MOTION_MODEL_NAMES
from poc_env.errors import ConfigError

KMH = 1000.0 / 3600.0
#: Largest speed a velocity field may hold, m/s: ocean surface currents stay below ~3 m/s; a
#: field above this is in the wrong unit (km/h, cm/s).
MAX_FIELD_MPS = 10.0
#: Largest 10 m wind a wind file may hold, m/s: above the strongest sustained winds measured
#: (~ 80 m/s in tropical cyclones); a file above this is in the wrong unit.
MAX_WIND_MPS = 90.0


@dataclass(frozen=True)
class LeewayClass:
    """Leeway of one search object class: downwind and crosswind leeway, each
    ``slope * W10 + offset``, slopes in % of the 10 m wind speed, offsets in cm/s; crosswind
    to the right (``+``) and to the left (``-``) of the downwind direction.

    Source of :data:`LEEWAY_CLASSES`: Allen, A. A. and Plourde, J. V. (1999), *Review of
    Leeway: Field Experiments and Implementation*, US Coast Guard R&D Center report
    CG-D-08-99, and Allen, A. A. (2005), *Leeway Divergence*, CG-D-05-05: the mean values of
    the USCG leeway taxonomy's classes as tabulated for SAROPS (2010) and in OpenDrift's
    ``OBJECTPROP.DAT`` (2011).
    """

    name: str
    description: str
    dwl_slope_pct: float
    dwl_offset_cms: float
    cwl_right_slope_pct: float
    cwl_right_offset_cms: float
    cwl_left_slope_pct: float
    cwl_left_offset_cms: float

    def leeway(self, wind_speed: float, side: float) -> tuple[float, float]:
        """(downwind, crosswind) leeway in m/s for a 10 m wind of ``wind_speed`` m/s;
        ``side`` +1 (right of downwind) or -1 (left); crosswind is positive to the right."""
        dw = self.dwl_slope_pct / 100.0 * wind_speed + self.dwl_offset_cms / 100.0
        if side >= 0:
            cw = self.cwl_right_slope_pct / 100.0 * wind_speed + self.cwl_right_offset_cms / 100.0
        else:
            cw = self.cwl_left_slope_pct / 100.0 * wind_speed + self.cwl_left_offset_cms / 100.0
        return dw, cw


#: Leeway classes: the mean values of the main classes of the US Coast Guard leeway taxonomy
#: (Allen, A. A. and Plourde, J. V., 1999, "Review of Leeway: Field Experiments and
#: Implementation", USCG R&D Center report CG-D-08-99; Allen, A. A., 2005, "Leeway Divergence",
#: CG-D-05-05), as tabulated for SAROPS (list of 2010-11-15) and reproduced in OpenDrift's
#: ``OBJECTPROP.DAT`` (2011-08-25): downwind slope [%] and offset [cm/s], crosswind (right,
#: left) slope [%] and offset [cm/s]. Left crosswind slopes are negative (to the left).
LEEWAY_CLASSES: dict[str, LeewayClass] = {
    c.name: c
    for c in (
        LeewayClass(
            "person_in_water", "PIW-1: person in water, unknown state", 0.96, 0.0, 0.54, 0.0,
            -0.54, 0.0,
        ),
        LeewayClass(
            "piw_vertical_pfd", "PIW-2: person in water, vertical, PFD type III, conscious",
            0.48, 0.0, 0.15, 0.0, -0.15, 0.0,
        ),
        LeewayClass(
            "life_raft_deep_ballast", "LIFE-RAFT-DB-10: life raft, deep ballast, general",
            3.52, -2.50, 0.62, -3.00, -0.45, -0.20,
        ),
        LeewayClass(
            "life_raft_no_ballast", "LIFE-RAFT-NB-1: life raft, no ballast, general", 3.70, 0.0,
            1.98, 0.0, -1.98, 0.0,
        ),
        LeewayClass(
            "skiff", "SKIFF-1: skiff, modified-v runabout outboard powerboat", 3.15, 0.0, 1.29,
            0.0, -1.29, 0.0,
        ),
        LeewayClass(
            "fishing_vessel", "FISHING-VESSEL-1: fishing vessel, general", 2.47, 0.0, 2.76, 0.0,
            -2.76, 0.0,
        ),
    )
}  # fmt: skip
if tuple(LEEWAY_CLASSES) != LEEWAY_CLASS_NAMES:  # the scenario loader's list and this table
    raise ImportError(f"leeway classes {tuple(LEEWAY_CLASSES)} differ from {LEEWAY_CLASS_NAMES}")


# ------------------------------------------------------------------------ velocity fields
@dataclass(frozen=True)
class VelocityField:
    """A gridded current on the map's cells: ``frames (T, 2, ny, nx)`` (east, north) in m/s,
    ``dt_s`` apart from the episode's start, linear in time between frames (a stationary field
    has ``T = 1``)."""

    frames: np.ndarray
    dt_s: float
    #: the frames' times (s from the episode's start; a file's own times, :mod:`poc_env.theory.
    #: fields`), or None: ``k dt_s``
    times_s: np.ndarray | None = None

    def at(self, t: float) -> np.ndarray:
        """The field ``(2, ny, nx)`` at time ``t`` (s), linear between frames (the first and
        last frames before and after them)."""
        if len(self.frames) == 1:
            return self.frames[0]
        if self.times_s is not None:
            ts = self.times_s
            if t <= ts[0]:
                return self.frames[0]
            if t >= ts[-1]:
                return self.frames[-1]
            k = int(np.searchsorted(ts, t, side="right")) - 1
            w = (t - ts[k]) / (ts[k + 1] - ts[k])
            return (1.0 - w) * self.frames[k] + w * self.frames[k + 1]
        x = min(max(t / self.dt_s, 0.0), len(self.frames) - 1.0)
        k = min(int(x), len(self.frames) - 2)
        w = x - k
        return (1.0 - w) * self.frames[k] + w * self.frames[k + 1]


def load_field(
    path: str,
    shape: tuple[int, int],
    span_s: float,
    dt_s: float | None,
    field: str,
    dt_key: str = "target.field_dt_s",
    top: float = MAX_FIELD_MPS,
) -> VelocityField:
    """Read and check a ``.npy`` velocity field for a map of ``shape`` (ny, nx) cells and an
    episode of ``span_s`` seconds: ConfigError naming ``field`` for a missing or unreadable
    file, a wrong shape, NaN or infinite values, speeds beyond :data:`MAX_FIELD_MPS` (wrong
    unit; ``top`` for a wind) or frames that end before the episode does (their spacing is
    ``dt_key``). Other formats: :func:`load_any_field`."""
    p = Path(path)
    if p.suffix != ".npy":
        raise ConfigError(field, path, "a .npy file of velocities (2, ny, nx) or (T, 2, ny, nx)")
    try:
        arr = np.load(p, allow_pickle=False, mmap_mode="r")  # the header, not yet the data
    except (OSError, ValueError) as err:
        raise ConfigError(field, path, f"a readable .npy file ({err})") from None
    want = f"(2, {shape[0]}, {shape[1]}) or (T, 2, {shape[0]}, {shape[1]}): east and north "
    if not isinstance(arr, np.ndarray):  # np.load reads a .npz archive by its content
        with contextlib.suppress(AttributeError):
            arr.close()
        raise ConfigError(
            field, f"{path}: a .npz archive ({type(arr).__name__})", want + "m/s (np.save)"
        )
    if arr.ndim == 3:
        arr = arr[None]
    if arr.ndim != 4 or arr.shape[1:] != (2, *shape) or arr.dtype.kind not in "iuf":
        raise ConfigError(field, f"{path} of shape {arr.shape}", want + "m/s on the map's cells")
    from poc_env.limits import check_memory

    check_memory(field, path, 8.0 * arr.size, "velocity field")
    arr = np.array(arr, dtype=float)  # read from the file now (a copy, not the memory map)
    if not np.all(np.isfinite(arr)):
        raise ConfigError(field, f"{path} with NaN or infinite values", "finite velocities")
    _check_speeds(arr, path, field, top)
    if len(arr) > 1:
        if dt_s is None:
            raise ConfigError(dt_key, dt_s, "the time between frames (s)")
        if (len(arr) - 1) * dt_s < span_s:
            raise ConfigError(
                field,
                f"{path}: {len(arr)} frames {dt_s:g} s apart",
                f"frames covering the episode's {span_s:g} s",
            )
    return VelocityField(arr, float(dt_s or 1.0))


def _check_speeds(arr: np.ndarray, path: str, field: str, limit: float = MAX_FIELD_MPS) -> None:
    top = float(np.hypot(arr[:, 0], arr[:, 1]).max())
    if top > limit:
        raise ConfigError(
            field, f"{path} with speeds up to {top:g}", f"m/s, at most {limit:g} (km/h?)"
        )


def load_any_field(
    target: Any, map_cfg: Any, shape: tuple[int, int], span_s: float, kind: str = "current"
) -> VelocityField:
    """The :class:`VelocityField` of ``target.field_file`` (``kind`` ``"current"``) or of
    ``target.wind_file`` (``"wind"``, the 10 m wind of ``leeway``) on a map of ``shape`` cells:
    a ``.npy`` on the map's cells (:func:`load_field`) or a ``.csv`` / CF ``.nc`` file read and
    interpolated onto the cells and the episode's span (:mod:`poc_env.theory.fields`: one
    reader for both kinds, which refuses a file of the other kind)."""
    pre = "field" if kind == "current" else "wind"
    path, start, dt_s = (getattr(target, f"{pre}_{k}") for k in ("file", "start", "dt_s"))
    field, start_key, dt_key = (f"target.{pre}_{k}" for k in ("file", "start", "dt_s"))
    top = MAX_FIELD_MPS if kind == "current" else MAX_WIND_MPS
    if Path(path).suffix.lower() == ".npy":
        if start is not None:
            raise ConfigError(start_key, start, "null for a .npy field")
        return load_field(path, shape, span_s, dt_s, field, dt_key, top)
    from poc_env.theory import fields

    if dt_s is not None:
        raise ConfigError(dt_key, dt_s, "null: the file has its times")
    if map_cfg is None:
        raise ValueError(f"{field} {path}: a .csv/.nc field needs the map (check's map_cfg)")
    raw = fields.read_field(path, kind)
    frames, times = fields.regrid(raw, map_cfg, shape, span_s, start)
    _check_speeds(frames, path, field, top)
    return VelocityField(frames, 1.0, times)


# ----------------------------------------------------------------------------- the table
@dataclass(frozen=True)
class MotionModel:
    """One motion model (module docstring).

    Attributes
    ----------
    name:
        The value of ``target.model``.
    moves:
        False: the predict step is skipped (``static``).
    uses_current, uses_field, uses_wind:
        Which of the configured velocities the model adds.
    equation:
        The model's velocity, as text (documentation).
    """

    name: str
    moves: bool
    uses_current: bool
    uses_field: bool
    uses_wind: bool
    equation: str


MODELS: dict[str, MotionModel] = {
    m.name: m
    for m in (
        MotionModel("static", False, False, False, False, "v = 0, D = 0 (the paper)"),
        MotionModel("diffusion", True, False, False, False, "v = 0; dp/dt = D lap p"),
        MotionModel(
            "drift", True, True, True, False,
            "v = current + field(x, t); dp/dt = -div(v p) + D lap p",
        ),
        MotionModel(
            "leeway", True, True, True, True,
            "v = current + field(x, t) + (a_d |W| + b_d) W/|W| + s (a_c |W| + b_c) W_perp, "
            "W = wind(x, t); + D lap p",
        ),
        MotionModel(
            "particles", True, False, False, False,
            "b' = P_k b: the particles' cell-to-cell transition (poc_env.theory.particles)",
        ),
    )
}  # fmt: skip
MODEL_NAMES = tuple(MODELS)
if MODEL_NAMES != MOTION_MODEL_NAMES:  # the scenario loader's list and this table: one set
    raise ImportError(f"motion models {MODEL_NAMES} differ from config's {MOTION_MODEL_NAMES}")


def motion_model(name: Any, field: str = "target.model") -> MotionModel:
    """The table entry of ``name``; ConfigError naming the models otherwise."""
    model = MODELS.get(name) if isinstance(name, str) else None
    if model is None:
        raise ConfigError(field, name, "one of " + ", ".join(MODELS))
    return model


def leeway_class(name: Any, field: str = "target.leeway_class") -> LeewayClass:
    """The leeway class ``name``; ConfigError naming the classes otherwise."""
    cls = LEEWAY_CLASSES.get(name) if isinstance(name, str) else None
    if cls is None:
        raise ConfigError(field, name, "one of " + ", ".join(LEEWAY_CLASSES))
    return cls


@dataclass(frozen=True)
class Motion:
    """The checked motion of one scenario: its model, ``D`` (m^2/s), the fixed uniform
    current (m/s), the random current's largest speed (m/s), the wind (m/s), the leeway class,
    the gridded current (or None) and the gridded 10 m wind (``target.wind_file``, m/s on the
    map's cells, or None: the uniform ``wind``)."""

    model: MotionModel
    diffusion: float
    current: tuple[float, float]
    random_current: float
    wind: tuple[float, float]
    leeway: LeewayClass | None
    field: VelocityField | None
    wind_field: VelocityField | None = None
    #: ``particles``: the trajectories that move the belief and the target
    particles: Any = None

    @property
    def moves(self) -> bool:
        return self.model.moves

    @property
    def gridded(self) -> bool:
        """The motion varies over the map (a current or a wind file, or particles): not one
        velocity per episode."""
        return self.field is not None or self.wind_field is not None or self.particles is not None

    def draw(self, rng: np.random.Generator) -> np.ndarray:
        """The episode's uniform velocity (2,) m/s (:meth:`draw_episode`)."""
        return self.draw_episode(rng)[0]

    def draw_episode(self, rng: np.random.Generator) -> tuple[np.ndarray, float]:
        """The episode's uniform velocity (2,) m/s and crosswind side: the fixed current, plus
        a random current (speed ``U(0, max)``, direction ``U(0, 2 pi)``) when
        ``random_current > 0``, plus (leeway) the leeway with its crosswind side drawn 50/50.
        With a wind file the leeway is not uniform: the velocity leaves it out and the side
        (+1 right, -1 left; 0 without leeway) picks the leeway field (:func:`cell_velocity`).
        Draws from ``rng`` only what the model uses, in the same order with or without a wind
        file."""
        v = np.zeros(2)
        side = 0.0
        if self.model.uses_current:
            v += self.current
            if self.random_current > 0:
                speed = rng.uniform(0.0, self.random_current)
                angle = rng.uniform(0.0, 2.0 * np.pi)
                v += speed * np.array([np.cos(angle), np.sin(angle)])
        if self.model.uses_wind and self.leeway is not None:
            side = 1.0 if rng.random() < 0.5 else -1.0
            if self.wind_field is None:
                v += leeway_velocity(self.leeway, self.wind, side)
        return v, side


def leeway_velocity(cls: LeewayClass, wind: Any, side: float) -> np.ndarray:
    """The leeway m/s of class ``cls`` in the 10 m ``wind`` (east, north; m/s; ``(2,)`` or
    ``(..., 2, ny, nx)`` frames, the result of the same shape): downwind along the wind,
    crosswind perpendicular to its right (``side`` +1) or left (-1); zero where there is no
    wind."""
    w = np.asarray(wind, dtype=float)
    if w.ndim == 1:
        speed = float(np.hypot(*w))
        if speed == 0.0:
            return np.zeros(2)
        down = w / speed
        right = np.array([down[1], -down[0]])  # the downwind direction turned 90 deg clockwise
        dw, cw = cls.leeway(speed, side)
        return dw * down + cw * right
    we, wn = w[..., 0, :, :], w[..., 1, :, :]
    speed = np.hypot(we, wn)
    calm = speed == 0.0
    safe = np.where(calm, 1.0, speed)
    de, dn = we / safe, wn / safe  # the downwind direction; right of it: (dn, -de)
    dw, cw = cls.leeway(speed, side)  # elementwise (the same formula as one wind)
    out = np.stack([dw * de + cw * dn, dw * dn - cw * de], axis=-3)
    return np.where(calm[..., None, :, :], 0.0, out)


def check(target: Any, shape: tuple[int, int], span_s: float, map_cfg: Any = None) -> Motion:
    """The :class:`Motion` of a scenario's ``target`` section (:class:`~poc_env.config.
    TargetConfig`) on a map of ``shape`` cells and an episode of ``span_s`` seconds (``map_cfg``:
    the scenario's :class:`~poc_env.config.MapConfig`, where a ``.csv``/``.nc`` field is placed);
    ConfigError naming the field for an unknown model or leeway class or a bad field file."""
    model = motion_model(target.model)
    unused = (  # a value the model ignores: refused, not silently dropped (issue 25 audit)
        ("current_kmh", any(target.current_kmh), model.uses_current, "drift or leeway"),
        ("random_current_kmh", target.random_current_kmh, model.uses_current, "drift or leeway"),
        ("wind_kmh", any(target.wind_kmh), model.uses_wind, "leeway"),
        ("diffusion_m2_s", target.diffusion_m2_s, model.moves, "any model but static"),
    )
    for key, given, used, models in unused:
        if given and not used:
            value = getattr(target, key)
            raise ConfigError(
                f"target.{key}",
                list(value) if isinstance(value, tuple) else value,
                f"0 with target.model {model.name!r}, which ignores it (it moves the target "
                f"with target.model {models})",
            )
    cls = leeway_class(target.leeway_class) if model.uses_wind else None
    field = None
    if target.field_file is not None:
        if not model.uses_field:
            raise ConfigError(
                "target.field_file", target.field_file, "null unless model is drift or leeway"
            )
        field = load_any_field(target, map_cfg, shape, span_s)
    lee = None
    wind_file = getattr(target, "wind_file", None)
    if wind_file is not None:
        if cls is None:
            raise ConfigError("target.wind_file", wind_file, "null unless model is leeway")
        if any(target.wind_kmh):
            raise ConfigError(
                "target.wind_kmh", list(target.wind_kmh), "[0, 0] with target.wind_file"
            )
        lee = load_any_field(target, map_cfg, shape, span_s, "wind")
    tracks = None
    if model.name == "particles":
        from poc_env.theory import particles

        if target.diffusion_m2_s:
            raise ConfigError(
                "target.diffusion_m2_s", target.diffusion_m2_s, "0: particles carry their spread"
            )
        if map_cfg is None:
            raise ValueError("target.particles_file: particles need the map (check's map_cfg)")
        tracks = particles.load_tracks(target.particles_file, map_cfg, span_s)
    return Motion(
        model=model,
        diffusion=float(target.diffusion_m2_s) if model.moves else 0.0,
        current=(target.current_kmh[0] * KMH, target.current_kmh[1] * KMH),
        random_current=float(target.random_current_kmh) * KMH,
        wind=(target.wind_kmh[0] * KMH, target.wind_kmh[1] * KMH),
        leeway=cls,
        field=field,
        wind_field=lee,
        particles=tracks,
    )


# ----------------------------------------------------------------------------- numerics
def substeps(u_max: float, v_max: float, diffusion: float, dt: float, h: float) -> int:
    """Sub-steps of one ``dt`` keeping ``(|u| + |v|) tau / h + 4 D tau / h^2 <= 1``."""
    return int(_kernel.substeps(float(u_max), float(v_max), float(diffusion), dt, h))


def advect_diffuse(
    mass: np.ndarray,
    u: np.ndarray,
    v: np.ndarray,
    diffusion: float,
    dt: float,
    h: float,
) -> np.ndarray:
    """Move the cell masses ``mass (E, NY, NX)`` (in place) for ``dt`` seconds by the cell
    velocities ``u, v`` (east, north; m/s; broadcastable to ``mass``) and diffusion ``D`` on
    cells of side ``h``; return the mass ``(E,)`` that left the map.

    Face velocities are the means of the two cells' (the edge cell's own at the map's edge);
    upwind advective and centred diffusive fluxes, explicit, in :func:`substeps` sub-steps;
    nothing enters from outside the map (compiled: :mod:`poc_env._kernels.motion`).
    """
    e, ny, nx = mass.shape
    u3 = _cells(u, e, ny, nx)
    v3 = _cells(v, e, ny, nx)
    # the largest face speed is at most the largest cell speed
    n = substeps(float(np.abs(u3).max()), float(np.abs(v3).max()), diffusion, dt, h)
    out = np.zeros(e)
    if u3.shape[1:] == v3.shape[1:] == (1, 1):  # one velocity per env: the stencil kernel
        uk, vk = u3[:, 0, 0].copy(), v3[:, 0, 0].copy()
        _kernel.advect_diffuse_uniform(mass, uk, vk, float(diffusion), dt / n, float(h), n, out)
    else:
        _kernel.advect_diffuse(mass, u3, v3, float(diffusion), dt / n, float(h), n, out)
    return out


def _cells(vel: np.ndarray, e: int, ny: int, nx: int) -> np.ndarray:
    """``vel`` as a float array (E, 1 | NY, 1 | NX) for the kernel."""
    a = np.asarray(vel, dtype=float)
    a = a.reshape((1,) * (3 - a.ndim) + a.shape) if a.ndim < 3 else a
    if a.shape[0] != e:
        a = np.broadcast_to(a, (e, *a.shape[1:]))
    return np.ascontiguousarray(a)


def _leeway_at(motion: Motion, t: float, side: Any) -> np.ndarray:
    """The leeway ``(E, 2, ny, nx)`` on the map's cells at time ``t`` of envs whose crosswind
    sides are ``side (E,)`` (the wind-file case)."""
    if side is None:  # a caller that knows one velocity per episode (a bound, a planner)
        raise ConfigError(
            "target.wind_file",
            "a gridded wind",
            "wind_kmh (a uniform wind) here: this use takes one velocity per episode, not each "
            "env's leeway side",
        )
    assert motion.wind_field is not None and motion.leeway is not None
    wind = motion.wind_field.at(t)  # the wind interpolated in time, then its leeway
    right, left = (leeway_velocity(motion.leeway, wind, k) for k in (1.0, -1.0))
    return np.where((np.asarray(side) >= 0)[:, None, None, None], right[None], left[None])


def cell_velocity(
    motion: Motion, uniform: np.ndarray, t: float, s: int, side: Any = None
) -> tuple[np.ndarray, np.ndarray]:
    """The velocities ``u, v`` of every env on the fine grid (``s`` fine cells per map cell):
    the episode's uniform velocity ``uniform (E, 2)`` plus the gridded current at time ``t``,
    plus (a wind file) the leeway of each env's crosswind ``side (E,)``."""
    u = uniform[:, 0, None, None]
    v = uniform[:, 1, None, None]
    if motion.field is not None:
        f = motion.field.at(t)
        fu = np.repeat(np.repeat(f[0], s, axis=0), s, axis=1)
        fv = np.repeat(np.repeat(f[1], s, axis=0), s, axis=1)
        u, v = u + fu[None], v + fv[None]
    if motion.wind_field is not None:
        lw = _leeway_at(motion, t, side)
        u = u + np.repeat(np.repeat(lw[:, 0], s, axis=1), s, axis=2)
        v = v + np.repeat(np.repeat(lw[:, 1], s, axis=1), s, axis=2)
    return u, v


def predict(
    motion: Motion,
    belief: np.ndarray,
    uniform: np.ndarray,
    t: float,
    dt: float,
    h: float,
    s: int,
    side: Any = None,
) -> np.ndarray:
    """The predict step of the filter on the fine belief ``(E, NY, NX)`` (in place) over
    ``[t, t + dt]`` (``side (E,)``: each env's crosswind side, for a wind file); returns the
    mass ``(E,)`` that left the map."""
    if motion.particles is not None:  # the particles' transition (uniform is 0)
        from poc_env.theory import particles

        return particles.predict(motion.particles, belief, t, dt, h)
    u, v = cell_velocity(motion, uniform, t, s, side)
    return advect_diffuse(belief, u, v, motion.diffusion, dt, h)


def predict_uniform(
    motion: Motion,
    belief: np.ndarray,
    drift: np.ndarray,
    mass_out: np.ndarray,
    target: np.ndarray,
    target_out: np.ndarray,
    noise: np.ndarray,
    step: np.ndarray,
    dt: float,
    h: float,
    origin: tuple[float, float],
    cell: float,
    shape: tuple[int, int],
) -> None:
    """The filter's whole predict step when every env has one velocity (no gridded field): as
    :func:`predict` then :func:`move_targets` (``noise (E, T, 2)`` read at ``min(step, T - 1)``),
    bit-identical to them, in one compiled call (:func:`poc_env._kernels.motion.
    predict_uniform`); everything in place, ``mass_out`` accumulated."""
    if motion.gridded:
        raise ValueError("predict_uniform: the motion has a gridded field; use predict")
    ny, nx = shape
    x0, y0 = origin
    _kernel.predict_uniform(
        belief, drift, float(motion.diffusion), float(dt), float(h), mass_out, target,
        target_out, noise, step, float(x0), float(y0), x0 + nx * cell, y0 + ny * cell,
    )  # fmt: skip


def move_targets(
    motion: Motion,
    target: np.ndarray,
    out: np.ndarray,
    uniform: np.ndarray,
    noise: np.ndarray,
    t: float,
    dt: float,
    origin: tuple[float, float],
    cell: float,
    shape: tuple[int, int],
    side: Any = None,
    which: Any = None,
) -> None:
    """Move the hidden targets ``target (E, 2)`` (in place) over ``[t, t + dt]``: ``x += v(x,
    t) dt + sqrt(2 D dt) noise`` (``noise (E, 2)`` standard normal; ``side (E,)`` each env's
    crosswind side, for a wind file), or (``particles``) by the displacement of the particle
    ``which (E,)`` each follows; a target outside the map (``out (E,)``, updated) no longer
    moves."""
    vel = np.array(uniform, dtype=float)
    ny, nx = shape
    if motion.particles is not None:
        from poc_env.theory import particles

        step = particles.displacement(motion.particles, np.asarray(which), t, t + dt)
    elif motion.gridded:
        i = np.clip(((target[:, 0] - origin[0]) // cell).astype(int), 0, nx - 1)
        j = np.clip(((target[:, 1] - origin[1]) // cell).astype(int), 0, ny - 1)
        if motion.field is not None:
            vel += motion.field.at(t)[:, j, i].T
        if motion.wind_field is not None:
            lw = _leeway_at(motion, t, side)
            vel += lw[np.arange(len(vel)), :, j, i]
    if motion.particles is None:
        step = vel * dt + math.sqrt(2.0 * motion.diffusion * dt) * noise
    target += np.where(out[:, None], 0.0, step)
    x0, y0 = origin
    outside = (
        (target[:, 0] < x0)
        | (target[:, 0] >= x0 + nx * cell)
        | (target[:, 1] < y0)
        | (target[:, 1] >= y0 + ny * cell)
    )
    out |= outside


# ------------------------------------------------------------------ the predict as a matrix
def substep_matrix(
    motion: Motion,
    uniform: np.ndarray,
    t: float,
    dt: float,
    h: float,
    s: int,
    shape,
    side: float | None = None,
) -> tuple[Any, int]:
    """The predict step of one env over ``[t, t + dt]`` (:func:`predict`, ``uniform (2,)`` its
    velocity) as a matrix: ``(S, n)`` with ``predict(x) = S^n x`` up to rounding, ``S`` the
    scipy CSR matrix ``(F, F)`` of one sub-step on the fine grid of ``shape`` (NY, NX),
    columns the cells the mass comes from (``1 - S^T 1`` leaves the map), ``n`` the sub-steps.

    ``S`` is *probed* from the filter's own kernel (:func:`advect_diffuse`, one sub-step), not
    re-derived: a sub-step moves mass only to the four neighbours, so the cells of one colour
    ``(i + 2 j) mod 5`` have disjoint neighbourhoods and five runs of the kernel (a one on
    every cell of a colour) give every column. Its transpose is the exact adjoint
    ``<S x, y> = <x, S^T y>`` for any field (:mod:`poc_env.theory.moving_bound`). ``side``:
    the episode's crosswind side (a wind file's leeway). For ``particles`` the step's
    transition matrix itself (``n == 1``, :mod:`poc_env.theory.particles`)."""
    from scipy import sparse

    ny, nx = shape
    if motion.particles is not None:
        return motion.particles.transition(t, dt, h, tuple(shape)).matrix, 1
    sides = None if side is None else np.array([side], dtype=float)
    u, v = cell_velocity(motion, np.asarray(uniform, dtype=float).reshape(1, 2), t, s, sides)
    u3, v3 = _cells(u, 5, ny, nx), _cells(v, 5, ny, nx)
    n = substeps(float(np.abs(u3).max()), float(np.abs(v3).max()), motion.diffusion, dt, h)
    jj, ii = np.mgrid[0:ny, 0:nx]
    colour = (ii + 2 * jj) % 5
    probe = (colour[None] == np.arange(5)[:, None, None]).astype(float)
    advect_diffuse(probe, u3, v3, motion.diffusion, dt / n, h)  # n == 1 sub-step of dt / n
    rows, cols, vals = [], [], []
    for dj, di in ((0, 0), (0, -1), (0, 1), (-1, 0), (1, 0)):
        ok = (jj + dj >= 0) & (jj + dj < ny) & (ii + di >= 0) & (ii + di < nx)
        j, i = jj[ok], ii[ok]
        rows.append((j + dj) * nx + i + di)
        cols.append(j * nx + i)
        vals.append(probe[colour[ok], j + dj, i + di])
    f = ny * nx
    coo = sparse.coo_array(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(f, f)
    )
    return coo.tocsr(), n
