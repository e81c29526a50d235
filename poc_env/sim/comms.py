"""Communication constraint (§3.2.4, eq. 24) and communication topologies (§3.2.5, Table 2).

Batched over envs: positions ``(n_envs, n_agents, 2)`` metres, adjacency matrices
``(n_envs, n, n)`` bool, symmetric, False on the diagonal. A *topology* is the set of undirected
links the swarm actually uses to pass data; two UAVs that are not linked directly can still
exchange data through relays (the paper's design principle), which :func:`reachable` computes.

Two topology rules (``CommsConfig.topology``):

- ``table2``: the paper's five-UAV topologies A-F and switching table (Table 2), shipped as data
  in ``configs/topologies/table2.yaml`` and applied by :class:`Table2Switcher`.
- ``auto``: any number of UAVs; :func:`auto_topology` builds a distance-weighted spanning forest
  of the available links plus each UAV's shortest links (see there).

Links become unavailable when out of range (eq. 24, :func:`in_range`), when a UAV is inactive,
or by random drops (:func:`link_failures`, from the caller's ``np.random.Generator``).
"""

from __future__ import annotations

import functools
import math
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import poc_env._kernels.swarm as _swarm
from poc_env.config import CONFIG_DIR, read_yaml
from poc_env.errors import ConfigError
from poc_env.sim.constraints import pairwise_distances

__all__ = [
    "AUTO",
    "TABLE2_PATH",
    "CommsTopology",
    "Table2Switcher",
    "TopologyTable",
    "adjacency_to_links",
    "auto_topology",
    "connected_components",
    "in_range",
    "link_failures",
    "links_to_adjacency",
    "load_topology_table",
    "reachable",
    "two_neighbour_ok",
]

#: The shipped Table 2 data file.
TABLE2_PATH = CONFIG_DIR / "topologies" / "table2.yaml"
#: Topology code of the general (``auto``) rule in :class:`Table2Switcher` results.
AUTO = -1

Link = tuple[int, int]


# --------------------------------------------------------------------------- graph basics


def links_to_adjacency(links: Iterable[Iterable[int]], n: int) -> np.ndarray:
    """Symmetric ``(n, n)`` bool adjacency from 0-based undirected links."""
    adj = np.zeros((n, n), dtype=bool)
    for i, j in links:
        adj[i, j] = adj[j, i] = True
    return adj


def adjacency_to_links(adj: np.ndarray) -> list[Link]:
    """Sorted 0-based links ``(i, j)``, ``i < j``, of one symmetric ``(n, n)`` adjacency."""
    i, j = np.nonzero(np.triu(np.asarray(adj, dtype=bool), k=1))
    return [(int(a), int(b)) for a, b in zip(i, j)]


def _active(active: np.ndarray | None, shape: tuple[int, ...]) -> np.ndarray:
    if active is None:
        return np.ones(shape, dtype=bool)
    return _shaped(active, shape, bool)


def _shaped(a: Any, shape: tuple[int, ...], dtype: Any) -> np.ndarray:
    """``a`` as a C-contiguous array of ``shape`` (broadcast if needed) and ``dtype``."""
    a = np.asarray(a, dtype=dtype)
    if a.shape != shape:
        a = np.broadcast_to(a, shape)
    return np.ascontiguousarray(a)


def in_range(
    xy: np.ndarray,
    range_m: float,
    active: np.ndarray | None = None,
    dist: np.ndarray | None = None,
) -> np.ndarray:
    """Adjacency ``(n_envs, n, n)``: pairs within communication range, ``D_ij <= RC_max`` (eq. 24).

    ``D_ij`` is the Euclidean distance over the given coordinates (2-D or 3-D). No self loops;
    an inactive UAV (``active (n_envs, n)`` False: landed or crashed) has no links. ``dist``
    optionally passes the already computed ``pairwise_distances(xy)``.
    """
    d = pairwise_distances(xy) if dist is None else np.asarray(dist, dtype=float)
    n_envs, n = d.shape[0], d.shape[-1]
    out = np.empty((n_envs, n, n), dtype=bool)
    _swarm.in_range(np.ascontiguousarray(d), float(range_m), _active(active, (n_envs, n)), out)
    return out


def two_neighbour_ok(
    adj: np.ndarray, min_neighbours: int = 2, active: np.ndarray | None = None
) -> np.ndarray:
    """Bool ``(n_envs, n)``: the communication constraint of §3.2.4 per UAV.

    The paper: a UAV meets the constraint when at least two *other* UAVs are within
    ``RC_max``. ``adj`` is an in-range adjacency (:func:`in_range`), so this counts each row.
    Without ``active`` the rule is literal. With ``active``, inactive UAVs are exempt (True) and
    the requirement is capped at ``n_active - 1`` in each env, so that a swarm reduced to one
    or two flying UAVs is not reported in violation of a rule it cannot meet.
    """
    a = np.asarray(adj, dtype=bool)
    n = a.shape[-1]
    shape = a.shape[:-1]
    act = np.ones((1, n), dtype=bool) if active is None else _active(active, shape)
    out = np.empty(shape, dtype=bool)
    _swarm.two_neighbour(
        np.ascontiguousarray(a).reshape(-1, n, n),
        int(min_neighbours),
        act.reshape(-1, n),
        active is not None,
        out.reshape(-1, n),
    )
    return out


def link_failures(adj: np.ndarray, prob: float, rng: np.random.Generator) -> np.ndarray:
    """Adjacency after random drops: each undirected link fails with probability ``prob``.

    One uniform draw per pair ``i < j`` per call from ``rng`` (shape ``(n_envs, n, n)``, upper
    triangle used), mirrored so the result stays symmetric. ``prob <= 0`` draws nothing and
    returns a copy, so enabling comms with no failures leaves the caller's random stream as is.
    """
    a = np.asarray(adj, dtype=bool)
    if prob <= 0:
        return a.copy()
    drop = np.triu(rng.random(a.shape) < float(prob), k=1)
    drop |= np.swapaxes(drop, -1, -2)
    return a & ~drop


def reachable(links_adj: np.ndarray) -> np.ndarray:
    """Transitive closure ``(n_envs, n, n)``: who can reach whom through relays.

    ``R[i, j]`` is True when a path of links joins ``i`` and ``j``; the diagonal is True (a UAV
    reaches itself). Computed by repeated boolean squaring of ``adj | I`` (``ceil(log2 n)``
    float32 matrix products, exact for counts below 2^24).
    """
    a = np.asarray(links_adj, dtype=bool)
    n = a.shape[-1]
    r = a | np.eye(n, dtype=bool)
    for _ in range(max(1, math.ceil(math.log2(max(n - 1, 1))))):
        f = r.astype(np.float32)
        r = (f @ f) > 0
    return r


def connected_components(
    links_adj: np.ndarray, active: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """``(n_components (n_envs,), labels (n_envs, n))`` of a symmetric link graph.

    A component's label is the smallest UAV index in it; inactive UAVs get label -1 and are
    not counted.
    """
    a = np.asarray(links_adj, dtype=bool)
    n_envs, n = a.shape[0], a.shape[-1]
    act = _active(active, (n_envs, n))
    a = a & act[:, :, None] & act[:, None, :]
    labels = np.argmax(reachable(a), axis=-1)
    labels = np.where(act, labels, -1)
    roots = labels == np.arange(n)
    return roots.sum(axis=-1), labels


# --------------------------------------------------------------------------- topologies


@dataclass(frozen=True)
class CommsTopology:
    """The links in use and the swarm's connectivity, per env."""

    #: ``(n_envs, n, n)`` bool, symmetric: the links data actually travels on.
    links: np.ndarray
    #: ``(n_envs,)`` bool: all active UAVs form one component (through relays).
    connected: np.ndarray
    #: ``(n_envs,)`` int: number of components among active UAVs.
    n_components: np.ndarray
    #: ``(n_envs,)`` int topology code of :class:`Table2Switcher` (``AUTO`` = -1 for the
    #: general rule); None for :func:`auto_topology`.
    topology: np.ndarray | None = None


def auto_topology(
    available: np.ndarray,
    xy: np.ndarray | None = None,
    active: np.ndarray | None = None,
    min_neighbours: int = 2,
    dist: np.ndarray | None = None,
) -> CommsTopology:
    """General topology rule for any number of UAVs (``comms.topology: auto``).

    The links used are the union of

    1. a minimum spanning forest of the available links, weighted by distance (Prim's
       algorithm, restarted in each component): it joins every pair of UAVs that the available
       graph joins, so the swarm is connected through relays exactly when the available
       (in-range, not dropped) graph is connected, with the shortest, most robust links;
    2. each UAV's ``min_neighbours`` shortest available links, so that every UAV has at least
       ``min(min_neighbours, its available degree)`` topology neighbours: the two-neighbour
       rule of §3.2.4 then holds on the topology wherever it holds on the in-range graph, and
       losing any one link of a UAV does not isolate it.

    Without ``xy`` all links weigh the same (any spanning forest). Ties go to the lower UAV
    index. Compiled (:func:`poc_env._kernels.swarm.auto_topology`): a loop over envs and the
    small graph.

    Parameters
    ----------
    available:
        ``(n_envs, n, n)`` bool usable links (e.g. ``link_failures(in_range(...))``).
    xy:
        ``(n_envs, n, 2)`` positions in metres, for the link weights.
    active:
        ``(n_envs, n)`` bool; inactive UAVs get no links and are not counted as components.
    dist:
        optional ``pairwise_distances(xy)``, when the caller already has it.
    """
    av = np.asarray(available, dtype=bool)
    n_envs, n = av.shape[0], av.shape[-1]
    act = _active(active, (n_envs, n))
    if dist is None and xy is not None:
        dist = pairwise_distances(xy)
    use_dist = dist is not None
    d = np.zeros((1, 1, 1)) if dist is None else _shaped(dist, (n_envs, n, n), float)
    links = np.empty((n_envs, n, n), dtype=bool)
    n_comp = np.empty(n_envs, dtype=np.int64)
    k_nearest = nearest_count(min_neighbours, n)
    av = _shaped(av, (n_envs, n, n), bool)
    _swarm.auto_topology(av, d, use_dist, act, k_nearest, links, n_comp)
    return CommsTopology(links=links, connected=n_comp <= 1, n_components=n_comp)


def nearest_count(min_neighbours: int, n: int) -> int:
    """How many shortest links per UAV :func:`auto_topology` adds: ``min_neighbours``, at most
    ``n - 1``, at least 0."""
    return max(min(int(min_neighbours), n - 1), 0)


@dataclass(frozen=True, eq=False)
class TopologyTable:
    """Named topologies and a lost-link switching table (Table 2), 0-based UAV indices."""

    n_uavs: int
    #: topology names in file order.
    names: tuple[str, ...]
    #: name -> sorted 0-based links.
    links: Mapping[str, tuple[Link, ...]]
    #: lost 0-based link ``(i, j)``, ``i < j`` -> topology name.
    switching: Mapping[Link, str]
    #: the starting topology.
    default: str

    @functools.cached_property
    def adjacency(self) -> np.ndarray:
        """``(n_topologies, n, n)`` bool adjacency, in the order of :attr:`names`."""
        return np.stack([links_to_adjacency(self.links[t], self.n_uavs) for t in self.names])

    def avoided(self, name: str) -> frozenset[Link]:
        """The table's lost links that switch to ``name``."""
        return frozenset(k for k, v in self.switching.items() if v == name)


def _link(field: str, value: Any, n: int) -> Link:
    ok = (
        isinstance(value, (list, tuple))
        and len(value) == 2
        and all(isinstance(v, int) and not isinstance(v, bool) and 1 <= v <= n for v in value)
        and value[0] != value[1]
    )
    if not ok:
        raise ConfigError(field, value, f"a pair [i, j] of distinct UAV numbers in 1..{n}")
    i, j = sorted(int(v) - 1 for v in value)
    return (i, j)


def _parse_table(data: Any, where: str) -> TopologyTable:
    allowed = {"n_uavs", "default", "topologies", "switching"}
    if not isinstance(data, dict):
        raise ConfigError(where, data, "a YAML mapping")
    unknown = sorted(set(data) - allowed)
    if unknown:
        raise ConfigError(f"{where}.{unknown[0]}", data[unknown[0]], "keys " + ", ".join(allowed))
    missing = sorted(allowed - set(data))
    if missing:
        raise ConfigError(f"{where}.{missing[0]}", None, "a required key")
    n = data["n_uavs"]
    if not isinstance(n, int) or isinstance(n, bool) or n < 2:
        raise ConfigError(f"{where}.n_uavs", n, "an integer >= 2")
    topos = data["topologies"]
    if not isinstance(topos, dict) or not topos:
        raise ConfigError(f"{where}.topologies", topos, "a mapping name -> list of [i, j] links")
    links: dict[str, tuple[Link, ...]] = {}
    for name, raw in topos.items():
        field = f"{where}.topologies.{name}"
        if not isinstance(name, str) or not name:
            raise ConfigError(field, name, "a non-empty topology name")
        if not isinstance(raw, list) or not raw:
            raise ConfigError(field, raw, "a non-empty list of [i, j] links")
        pairs = [_link(f"{field}[{k}]", v, n) for k, v in enumerate(raw)]
        if len(set(pairs)) != len(pairs):
            raise ConfigError(field, raw, "links listed once each")
        adj = links_to_adjacency(pairs, n)
        n_comp, _ = connected_components(adj[None])
        if n_comp[0] != 1:
            raise ConfigError(
                field, raw, "a connected topology (every UAV reachable through relays)"
            )
        links[name] = tuple(sorted(pairs))
    default = data["default"]
    if default not in links:
        raise ConfigError(f"{where}.default", default, "one of " + ", ".join(links))
    rows = data["switching"]
    if not isinstance(rows, list) or not rows:
        raise ConfigError(f"{where}.switching", rows, "a list of {lost: [i, j], topology: X}")
    switching: dict[Link, str] = {}
    for k, row in enumerate(rows):
        field = f"{where}.switching[{k}]"
        if not isinstance(row, dict) or set(row) != {"lost", "topology"}:
            raise ConfigError(field, row, "a mapping {lost: [i, j], topology: X}")
        lost = _link(f"{field}.lost", row["lost"], n)
        target = row["topology"]
        if target not in links:
            raise ConfigError(f"{field}.topology", target, "one of " + ", ".join(links))
        if lost in switching:
            raise ConfigError(f"{field}.lost", row["lost"], "each lost link listed once")
        if lost in links[target]:
            raise ConfigError(
                f"{field}.topology", target, f"a topology without the lost link {row['lost']}"
            )
        switching[lost] = target
    return TopologyTable(
        n_uavs=n, names=tuple(links), links=links, switching=switching, default=default
    )


@functools.lru_cache(maxsize=8)
def _load_cached(path: str) -> TopologyTable:
    try:
        data = read_yaml(path)
    except ConfigError as err:
        raise ConfigError("topology_file", path, err.allowed) from None
    return _parse_table(data, Path(path).name)


def load_topology_table(path: str | os.PathLike[str] | None = None) -> TopologyTable:
    """Load and validate a topology file (default: the shipped Table 2, 1-based UAV numbers).

    Checks: known keys only; links are pairs of distinct UAV numbers in ``1..n_uavs``, listed
    once; every topology is connected; ``default`` names a topology; each switching row names a
    known topology that does not use the lost link. Errors are :class:`ConfigError` naming the
    file and the field.
    """
    return _load_cached(str(Path(path) if path is not None else TABLE2_PATH))


class Table2Switcher:
    """Topology switching by Table 2 (§3.2.5), batched over envs.

    State per env is a topology code: an index into :attr:`names`, or ``AUTO`` (-1) when the
    general rule (:func:`auto_topology`) is in use. Each step, given the available links:

    1. if the current named topology uses no lost link, keep it (lost links it does not use do
       not matter);
    2. otherwise take the lost links in sorted order, first those of the current topology, then
       the others, and switch to the table entry of the first one whose topology uses no lost
       link (the first lost link of the current topology decides whenever its entry works);
    3. otherwise any topology that uses no lost link, the default first, then file order (this
       also brings an env back from ``AUTO`` once links recover);
    4. otherwise the general rule on the available links (code ``AUTO``).

    A "lost" link is any pair of distinct UAVs not in ``available`` (out of range, dropped, or
    involving an inactive UAV). The shipped table is for exactly five UAVs.
    """

    def __init__(
        self,
        table: TopologyTable | None = None,
        n_agents: int | None = None,
        min_neighbours: int = 2,
    ) -> None:
        self.table = table if table is not None else load_topology_table()
        t = self.table
        if n_agents is not None and n_agents != t.n_uavs:
            raise ConfigError(
                "comms.topology",
                "table2",
                f"'auto', or 'table2' with exactly {t.n_uavs} UAVs (the swarm has {n_agents})",
            )
        self.min_neighbours = int(min_neighbours)
        self._adj = t.adjacency
        self._index = {name: k for k, name in enumerate(t.names)}
        pairs = sorted(t.switching)
        self._pi = np.array([p[0] for p in pairs], dtype=np.intp)
        self._pj = np.array([p[1] for p in pairs], dtype=np.intp)
        self._target = np.array([self._index[t.switching[p]] for p in pairs], dtype=np.intp)
        d = self._index[t.default]
        self._order = np.array([d] + [k for k in range(len(t.names)) if k != d], dtype=np.intp)

    @property
    def names(self) -> tuple[str, ...]:
        return self.table.names

    @property
    def n(self) -> int:
        return self.table.n_uavs

    def code(self, name: str | None) -> int:
        """Topology code of ``name`` (None -> ``AUTO``)."""
        if name is None:
            return AUTO
        if name not in self._index:
            raise ConfigError("topology", name, "one of " + ", ".join(self.names))
        return self._index[name]

    def name(self, code: int) -> str | None:
        """Topology name of ``code`` (``AUTO`` -> None)."""
        return None if code == AUTO else self.names[int(code)]

    def initial(self, n_envs: int) -> np.ndarray:
        """Codes ``(n_envs,)`` of the default topology."""
        return np.full(n_envs, self._index[self.table.default], dtype=np.intp)

    def switch(
        self,
        current: np.ndarray,
        available: np.ndarray,
        xy: np.ndarray | None = None,
        active: np.ndarray | None = None,
    ) -> CommsTopology:
        """Next topology per env from ``current (n_envs,)`` codes and ``available (n_envs,n,n)``.

        ``xy`` weights the general rule's links by distance when it is needed. Returns the new
        codes in ``.topology`` and the links, connectivity and component count per env.
        """
        av = np.asarray(available, dtype=bool)
        n_envs, n = av.shape[0], av.shape[-1]
        if n != self.n:
            raise ConfigError("available", av.shape, f"adjacency of exactly {self.n} UAVs")
        act = _active(active, (n_envs, n))
        av = av & act[:, :, None] & act[:, None, :]
        cur = np.broadcast_to(np.asarray(current, dtype=np.intp), (n_envs,))
        envs = np.arange(n_envs)
        lost = ~av & ~np.eye(n, dtype=bool)
        ok = ~np.any(self._adj[None] & lost[:, None], axis=(-1, -2))  # (n_envs, T)
        named = cur >= 0
        cur_c = np.where(named, cur, 0)
        stay = named & ok[envs, cur_c]
        # rule 2: table entries of lost links, current topology's links first, sorted
        n_pairs = len(self._pi)
        lost_p = lost[:, self._pi, self._pj]
        in_cur = named[:, None] & self._adj[cur_c][:, self._pi, self._pj]
        rank = np.arange(n_pairs) + np.where(in_cur, 0, n_pairs)
        key = np.where(lost_p & ok[:, self._target], rank, 2 * n_pairs)
        best = np.argmin(key, axis=-1)
        by_table = key[envs, best] < 2 * n_pairs
        # rule 3: any intact topology, default first
        ok_ord = ok[:, self._order]
        by_any = ok_ord.any(axis=-1)
        any_code = self._order[np.argmax(ok_ord, axis=-1)]
        new = np.where(
            stay,
            cur,
            np.where(by_table, self._target[best], np.where(by_any, any_code, AUTO)),
        )
        links = self._adj[np.where(new >= 0, new, 0)].copy()
        fallback = new == AUTO
        if fallback.any():
            sub_xy = None if xy is None else np.asarray(xy, dtype=float)[fallback]
            links[fallback] = auto_topology(
                av[fallback], sub_xy, act[fallback], self.min_neighbours
            ).links
        n_comp, _ = connected_components(links, act)
        return CommsTopology(links=links, connected=n_comp <= 1, n_components=n_comp, topology=new)

    def next_topology(self, current: str | None, lost: Iterable[Iterable[int]]) -> str | None:
        """Single-env form of :meth:`switch`: the next topology name (None = general rule).

        ``lost`` holds 0-based pairs of UAVs that cannot communicate.
        """
        avail = ~np.eye(self.n, dtype=bool)
        for i, j in lost:
            avail[i, j] = avail[j, i] = False
        codes = self.switch(np.array([self.code(current)]), avail[None]).topology
        assert codes is not None
        return self.name(int(codes[0]))
