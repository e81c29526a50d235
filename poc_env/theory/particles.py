"""Particle trajectories as the target's motion model (``target.model: particles``, issue 25).

An OpenDrift user runs a drift model (Leeway, OceanDrift) from the last known position and gets
``N`` particle trajectories; each is an equally likely path of the lost object. Here those
trajectories *are* the motion model: the filter's predict step moves the belief as the
particles move, and the hidden target follows one particle.

The predict step (:meth:`ParticleTracks.transition`) is the empirical Markov transition between
the belief's fine cells over one env step ``[t_k, t_k + dt]``: of the ``m_c`` particles in fine
cell ``c`` at ``t_k``, ``m_{c -> c'}`` are in ``c'`` at ``t_k + dt``, so

    b'(c') = sum_c  m_{c -> c'} / m_c  b(c),     out += sum_c  m_{c -> out} / m_c  b(c),

a column-stochastic sparse matrix ``P_k`` (``scipy.sparse`` CSR; its exact transpose is
``P_k.T``, the adjoint a moving-target bound needs) plus the fraction of each cell's mass that
leaves the map (added to ``mass_out``: nothing re-enters, as the grid filter's absorbing edge).
Mass is conserved to rounding: every column of ``P_k`` plus its ``out`` fraction sums to
``m_c / m_c``. Fallback: a cell no particle occupies at ``t_k`` keeps its mass (the identity
column) -- the particles say nothing about it. Positions between the file's output times are
linear in time (resampled to the env's ``dt``), as OpenDrift's own interpolation of its output.

The estimate forgets where inside a cell each particle sits (a Markov chain on cells), which
adds a first-order numerical spreading of the same kind and size as the grid filter's upwind
advection (:func:`poc_env.theory.motion.advect_diffuse`): for particles carried by a uniform
current the two filters agree (``tests/theory/test_particles.py`` states by how much). Few
particles per cell make the transition noisy: :data:`MIN_PARTICLES` is a floor, not a target
(OpenDrift's SAR runs use thousands).

The hidden target (:func:`pick_particle`): drawn from the prior as for every model, it then
follows one particle drawn (from the episode's generator) among those in its fine cell at the
start: ``x(t) = x(0) + (p(t) - p(0))``, so the truth moves exactly as a particle does; a target
whose cell holds no particle stays put (the fallback above). A target leaving the map stays out.

The file (``target.particles_file``, written by ``poc-env scenario import --particles FILE.nc
--particle-motion``): an ``.npz`` with ``lon``, ``lat`` ``(N, T)`` WGS84 degrees of the
particles active at the episode's start (a particle deactivated later, stranded, holds its last
position), ``t_s (T,)`` seconds from the episode's start, and ``start`` (ISO 8601). Positions
are placed on the map by its ``origin_deg`` and ``projection`` when the dynamics are built, so
the file does not depend on the grid or ``dt``.
"""

from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from poc_env.errors import ConfigError

FIELD = "target.particles_file"
#: Fewest particles a particle motion accepts: fewer estimate a cell's transition from one or
#: two particles (OpenDrift's SAR runs use thousands).
MIN_PARTICLES = 100
#: Transitions kept per tracks object (an env batch is at a few distinct steps at once).
CACHE = 16


@dataclass(frozen=True)
class Transition:
    """One step's predict: ``matrix (n, n)`` CSR, column ``c`` the share of cell ``c``'s mass
    in each cell after the step; ``out (n,)`` the share that left the map."""

    matrix: Any
    out: np.ndarray


@dataclass(frozen=True, eq=False)
class ParticleTracks:
    """Particle positions ``x, y (N, T)`` in metres from the map's origin corner
    (``map.origin_km``: the fine cell ``(j, i)`` holds ``i h <= x < (i + 1) h``, ``j h <= y <
    (j + 1) h``), at ``times_s (T,)`` from the episode's start (``times_s[0] <= 0``)."""

    x: np.ndarray
    y: np.ndarray
    times_s: np.ndarray
    path: str = ""
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def n(self) -> int:
        return int(self.x.shape[0])

    def positions(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Every particle's ``(x, y)`` at time ``t`` (s), linear between output times."""
        ts = self.times_s
        if not ts[0] <= t <= ts[-1]:
            raise ValueError(f"t = {t} s outside the particles' times {ts[0]}..{ts[-1]} s")
        if len(ts) == 1:
            return self.x[:, 0], self.y[:, 0]
        k = min(int(np.searchsorted(ts, t, side="right")) - 1, len(ts) - 2)
        w = (t - ts[k]) / (ts[k + 1] - ts[k])
        if w == 0.0:
            return self.x[:, k], self.y[:, k]
        return (
            (1.0 - w) * self.x[:, k] + w * self.x[:, k + 1],
            (1.0 - w) * self.y[:, k] + w * self.y[:, k + 1],
        )

    def cells(self, t: float, h: float, shape: tuple[int, int]) -> np.ndarray:
        """Every particle's flat fine cell ``j nx + i`` at ``t`` (``ny nx`` outside the map)."""
        ny, nx = shape
        x, y = self.positions(t)
        i = np.floor(x / h)
        j = np.floor(y / h)
        inside = (i >= 0) & (i < nx) & (j >= 0) & (j < ny)
        return np.where(inside, j * nx + i, ny * nx).astype(np.int64)

    def transition(self, t: float, dt: float, h: float, shape: tuple[int, int]) -> Transition:
        """The predict of ``[t, t + dt]`` on fine cells of side ``h``, ``shape`` (module
        docstring); cached (the last :data:`CACHE`)."""
        key = (float(t), float(dt), float(h), tuple(shape))
        hit = self._cache.get(key)
        if hit is not None:
            return hit
        from scipy import sparse

        n = shape[0] * shape[1]
        end = float(self.times_s[-1])  # past the tracks (never in an episode): nothing moves
        c0 = self.cells(min(t, end), h, shape)
        c1 = self.cells(min(t + dt, end), h, shape)
        live = c0 < n  # particles outside the map at t say nothing about the cells
        c0, c1 = c0[live], c1[live]
        count = np.bincount(c0, minlength=n).astype(float)
        share = 1.0 / count[c0]
        stay = np.flatnonzero(count == 0)  # the fallback: cells without particles keep mass
        into = c1 < n
        rows = np.concatenate([c1[into], stay])
        cols = np.concatenate([c0[into], stay])
        data = np.concatenate([share[into], np.ones(len(stay))])
        matrix = sparse.csr_matrix((data, (rows, cols)), shape=(n, n))  # duplicates summed
        matrix.sum_duplicates()
        out = np.bincount(c0[~into], weights=share[~into], minlength=n)
        result = Transition(matrix, out)
        if len(self._cache) >= CACHE:
            self._cache.pop(next(iter(self._cache)))
        self._cache[key] = result
        return result


def predict(
    tracks: ParticleTracks, belief: np.ndarray, t: float, dt: float, h: float
) -> np.ndarray:
    """Move the fine beliefs ``belief (E, NY, NX)`` (in place) over ``[t, t + dt]`` by the
    particles' transition; return the mass ``(E,)`` that left the map."""
    e, ny, nx = belief.shape
    tr = tracks.transition(t, dt, h, (ny, nx))
    from poc_env._kernels.motion import csr_apply

    flat = np.ascontiguousarray(belief.reshape(e, ny * nx), dtype=float)
    out = flat @ tr.out
    moved = np.empty_like(flat)
    m = tr.matrix  # every env's belief times the same CSR matrix, compiled
    csr_apply(m.indptr, m.indices, m.data, flat, moved)
    belief[...] = moved.reshape(e, ny, nx)
    return np.asarray(out, dtype=float)


def pick_particle(
    tracks: ParticleTracks, target: np.ndarray, h: float, shape: tuple[int, int], rng
) -> int:
    """The particle a hidden target at ``target (2,)`` (metres from the map's origin corner)
    follows: one drawn uniformly by ``rng`` among those in its fine cell at time 0, or -1
    when none is (the target then stays put)."""
    ny, nx = shape
    i, j = math.floor(target[0] / h), math.floor(target[1] / h)
    if not (0 <= i < nx and 0 <= j < ny):
        return -1
    here = np.flatnonzero(tracks.cells(0.0, h, shape) == j * nx + i)
    if not len(here):
        return -1
    return int(here[rng.integers(len(here))])


def displacement(tracks: ParticleTracks, which: np.ndarray, t0: float, t1: float) -> np.ndarray:
    """``(E, 2)`` the displacement of particles ``which (E,)`` from ``t0`` to ``t1`` (zero
    for -1)."""
    end = float(tracks.times_s[-1])
    x0, y0 = tracks.positions(min(t0, end))
    x1, y1 = tracks.positions(min(t1, end))
    k = np.maximum(which, 0)
    d = np.column_stack([x1[k] - x0[k], y1[k] - y0[k]])
    return np.where((which >= 0)[:, None], d, 0.0)


# --------------------------------------------------------------------------------- files
def tracks_from_lonlat(
    lon: Any, lat: Any, t_s: Any, map_cfg: Any, span_s: float, path: str = "", local: bool = False
) -> ParticleTracks:
    """Checked :class:`ParticleTracks` from ``lon, lat (N, T)`` WGS84 degrees at ``t_s (T,)``
    seconds from the episode's start, placed on the map ``map_cfg`` (its ``origin_deg`` and
    ``projection``) for an episode of ``span_s`` seconds. ConfigError naming
    ``target.particles_file``: non-finite or out-of-range positions, shapes that differ, fewer
    than :data:`MIN_PARTICLES` particles, times not increasing or not covering ``[0, span_s]``,
    a map without ``origin_deg``. ``local``: ``lon, lat`` are the scenario's local metres
    (x, y), placed without a CRS."""
    lon = np.asarray(lon, dtype=float)
    lat = np.asarray(lat, dtype=float)
    t = np.asarray(t_s, dtype=float).ravel()
    shown = path or "particle tracks"
    if lon.ndim != 2 or lon.shape != lat.shape or lon.shape[1] != len(t) or not len(t):
        raise ConfigError(
            FIELD,
            f"{shown}: lon {lon.shape}, lat {lat.shape}, t_s {t.shape}",
            "lon and lat (particles, times) and t_s (times,)",
        )
    if lon.shape[0] < MIN_PARTICLES:
        raise ConfigError(
            FIELD,
            f"{shown}: {lon.shape[0]} particles",
            f"at least {MIN_PARTICLES} particles active at the episode's start (a transition "
            "estimated from a few particles is noise)",
        )
    if not (np.all(np.isfinite(lon)) and np.all(np.isfinite(lat)) and np.all(np.isfinite(t))):
        raise ConfigError(FIELD, f"{shown} with NaN or infinite values", "finite positions")
    if not local and (np.any(np.abs(lat) > 90.0) or np.any(np.abs(lon) > 360.0)):
        raise ConfigError(FIELD, f"{shown}: latitudes beyond 90", "WGS84 degrees")
    if np.any(np.diff(t) <= 0):
        raise ConfigError(FIELD, f"{shown}: times not increasing", "strictly increasing t_s")
    if t[0] > 0.0 or t[-1] < span_s:
        raise ConfigError(
            FIELD,
            f"{shown}: times from {t[0]:g} s to {t[-1]:g} s of the episode's start",
            f"trajectories covering the episode: 0 to {span_s:g} s",
        )
    if local:
        xy = np.column_stack([lon.ravel(), lat.ravel()])
    else:
        from poc_env.crs import to_local
        from poc_env.theory.fields import _map_crs

        rec = _map_crs(map_cfg, shown)
        xy = np.asarray(to_local(np.column_stack([lat.ravel(), lon.ravel()]), rec), dtype=float)
    x0, y0 = map_cfg.origin_m
    x = (xy[:, 0] - x0).reshape(lon.shape)
    y = (xy[:, 1] - y0).reshape(lon.shape)
    return ParticleTracks(np.ascontiguousarray(x), np.ascontiguousarray(y), t, shown)


def load_tracks(path: str, map_cfg: Any, span_s: float) -> ParticleTracks:
    """Read and check the ``.npz`` ``target.particles_file`` (module docstring): ``lon``,
    ``lat`` (WGS84 degrees, placed by the map's CRS) or ``x_m``, ``y_m`` (the scenario's local
    metres), and ``t_s``."""
    p = Path(path)
    if p.suffix.lower() != ".npz" or not p.is_file():
        raise ConfigError(
            FIELD, path, "an existing .npz of particle tracks (poc-env scenario import "
            "--particles FILE.nc --particle-motion)",
        )  # fmt: skip
    try:
        data = np.load(p, allow_pickle=False)
    except (OSError, ValueError) as err:
        raise ConfigError(FIELD, path, f"a readable .npz file ({err})") from None
    if not hasattr(data, "files"):  # a .npy named .npz
        raise ConfigError(FIELD, path, "an .npz archive with lon, lat, t_s")
    with contextlib.closing(data):
        names = ("x_m", "y_m", "t_s") if "x_m" in data.files else ("lon", "lat", "t_s")
        missing = [k for k in names if k not in data.files]
        if missing:
            raise ConfigError(
                FIELD, f"{path} with {sorted(data.files)}", "arrays lon, lat (or x_m, y_m), t_s"
            )
        from poc_env.limits import check_memory

        check_memory(FIELD, path, 4 * 8.0 * np.prod(data[names[0]].shape), "particle tracks")
        arrays = [data[k] for k in names]
    if any(a.dtype.kind not in "iuf" for a in arrays):
        raise ConfigError(FIELD, path, f"numeric {', '.join(names)}")
    local = names[0] == "x_m"
    lon, lat, t_s = arrays
    return tracks_from_lonlat(lon, lat, t_s, map_cfg, span_s, str(path), local=local)
