"""Tests of the communication constraint (eq. 24), Table 2 topologies and the auto relay rule."""

from __future__ import annotations

import itertools
from collections import deque

import numpy as np
import pytest

from poc_env.errors import ConfigError
from poc_env.sim.comms import (
    AUTO,
    TABLE2_PATH,
    Table2Switcher,
    adjacency_to_links,
    auto_topology,
    connected_components,
    in_range,
    link_failures,
    links_to_adjacency,
    load_topology_table,
    reachable,
    two_neighbour_ok,
)

R = 10_000.0  # communication range, metres

# Table 2 of the paper, 1-based: lost link -> topology
TABLE2 = {
    (1, 2): "B",
    (1, 3): "C",
    (1, 4): "B",
    (1, 5): "C",
    (2, 3): "A",
    (2, 4): "B",
    (2, 5): "A",
    (3, 4): "E",
    (3, 5): "C",
    (4, 5): "F",
}


def bfs_closure(adj: np.ndarray) -> np.ndarray:
    """Reference closure of one (n, n) graph by breadth-first search."""
    n = len(adj)
    out = np.zeros((n, n), dtype=bool)
    for s in range(n):
        seen = {s}
        todo = deque([s])
        while todo:
            u = todo.popleft()
            for v in np.nonzero(adj[u])[0]:
                if int(v) not in seen:
                    seen.add(int(v))
                    todo.append(int(v))
        out[s, list(seen)] = True
    return out


def bfs_connected(adj: np.ndarray, active: np.ndarray) -> bool:
    idx = np.nonzero(active)[0]
    if len(idx) <= 1:
        return True
    return bool(bfs_closure(adj)[idx[0], idx].all())


def random_swarm(rng, n_envs, n, spread):
    return rng.uniform(0, spread, size=(n_envs, n, 2))


# ------------------------------------------------------------------ eq. 24 and §3.2.4


def test_in_range_symmetric_no_self_loops_and_inactive():
    rng = np.random.default_rng(0)
    xy = random_swarm(rng, 16, 7, 30_000)
    active = rng.random((16, 7)) > 0.2
    adj = in_range(xy, R, active)
    assert adj.shape == (16, 7, 7) and adj.dtype == bool
    np.testing.assert_array_equal(adj, np.swapaxes(adj, 1, 2))
    assert not adj[:, np.arange(7), np.arange(7)].any()
    assert not adj[~active].any()
    d = np.linalg.norm(xy[:, :, None] - xy[:, None], axis=-1)
    want = (d <= R) & ~np.eye(7, dtype=bool) & active[:, :, None] & active[:, None, :]
    np.testing.assert_array_equal(adj, want)
    assert 0 < adj.sum() < want.size  # a real mix
    # exactly at the range counts (eq. 24 is <=)
    two = np.array([[[0.0, 0.0], [R, 0.0]]])
    assert in_range(two, R)[0, 0, 1]


def test_two_neighbour_rule_line_of_four():
    xy = np.array([[[0.9 * R * k, 0.0] for k in range(4)]])
    adj = in_range(xy, R)
    np.testing.assert_array_equal(adj.sum(-1), [[1, 2, 2, 1]])
    np.testing.assert_array_equal(two_neighbour_ok(adj), [[False, True, True, False]])
    np.testing.assert_array_equal(two_neighbour_ok(adj, min_neighbours=1), [[True] * 4])
    np.testing.assert_array_equal(two_neighbour_ok(adj, min_neighbours=3), [[False] * 4])


def test_two_neighbour_rule_with_inactive_agents():
    # a triangle plus a far UAV; then only two UAVs left flying
    xy = np.array([[[0, 0], [5000, 0], [0, 5000], [90_000, 0]]], dtype=float)
    adj = in_range(xy, R)
    np.testing.assert_array_equal(two_neighbour_ok(adj), [[True, True, True, False]])
    active = np.array([[True, True, False, False]])
    adj = in_range(xy, R, active)
    np.testing.assert_array_equal(two_neighbour_ok(adj), [[False, False, False, False]])
    # with the mask: inactive exempt, requirement capped at n_active - 1 = 1
    np.testing.assert_array_equal(two_neighbour_ok(adj, 2, active), [[True, True, True, True]])


# ------------------------------------------------------------------ Table 2


def test_table_file_matches_paper_table2():
    t = load_topology_table()
    assert t.n_uavs == 5 and t.default == "D"
    assert set(t.names) == set("ABCDEF")
    assert {(i + 1, j + 1): v for (i, j), v in t.switching.items()} == TABLE2


@pytest.mark.parametrize("name", list("ABCDEF"))
def test_each_topology_avoids_exactly_its_table_links_and_is_connected(name):
    t = load_topology_table()
    assigned = {(i - 1, j - 1) for (i, j), v in TABLE2.items() if v == name}
    all_pairs = set(itertools.combinations(range(5), 2))
    links = set(t.links[name])
    assert all_pairs - links == assigned  # avoids exactly these
    assert t.avoided(name) == assigned
    adj = links_to_adjacency(links, 5)
    assert bfs_closure(adj).all()  # connected through relays
    assert adj.sum(-1).min() >= 2  # every UAV keeps two neighbours
    # robust: still connected after losing any one further link
    for i, j in links:
        cut = adj.copy()
        cut[i, j] = cut[j, i] = False
        assert bfs_closure(cut).all()


def test_paper_example_a_loses_3_4_goes_to_e_via_uav_1():
    t = load_topology_table()
    s = Table2Switcher(n_agents=5)
    assert (2, 3) in t.links["A"]  # topology A must contain 3-4 (0-based 2-3)
    assert s.next_topology("A", [(2, 3)]) == "E"
    e = set(t.links["E"])
    assert (2, 3) not in e and (0, 2) in e and (0, 3) in e  # 3-1-4 relay path


@pytest.mark.parametrize(("lost", "target"), sorted(TABLE2.items()))
def test_each_table2_row_switches_to_listed_topology(lost, target):
    t = load_topology_table()
    s = Table2Switcher(n_agents=5)
    pair = (lost[0] - 1, lost[1] - 1)
    froms = [name for name in t.names if pair in t.links[name]]
    assert "D" in froms
    for current in froms:
        assert s.next_topology(current, [pair]) == target
    # a topology that does not use the lost link is kept
    assert s.next_topology(target, [pair]) == target
    # batched form: the links returned avoid the lost link and are connected
    avail = np.broadcast_to(~np.eye(5, dtype=bool), (len(froms), 5, 5)).copy()
    avail[:, pair[0], pair[1]] = avail[:, pair[1], pair[0]] = False
    out = s.switch(np.array([s.code(c) for c in froms]), avail)
    assert [s.name(c) for c in out.topology] == [target] * len(froms)
    assert not out.links[:, pair[0], pair[1]].any()
    assert out.connected.all() and (out.n_components == 1).all()
    for links in out.links:
        assert bfs_closure(links).all()


def test_switch_multiple_losses_and_fallback():
    s = Table2Switcher(n_agents=5)
    # 1-2 and 1-4 lost: both rows say B, and B avoids both
    assert s.next_topology("D", [(0, 1), (0, 3)]) == "B"
    # 1-2 and 3-4 lost: B uses 3-4, E uses 1-2, no topology avoids both -> general rule
    assert s.next_topology("D", [(0, 1), (2, 3)]) is None
    assert s.next_topology("D", [(0, 1), (1, 2)]) is None
    # from the general rule, back to the default once everything is in range
    assert s.next_topology(None, []) == "D"
    # a lost link the current topology does not use changes nothing
    assert s.next_topology("E", [(2, 3)]) == "E"
    assert s.next_topology("E", [(2, 3), (0, 1)]) is None


def test_switch_rule_order_on_custom_table(tmp_path):
    # P uses 1-2 and 3-4. Losing both: 1-2's entry X still uses 3-4, so 3-4's entry Y is
    # taken (rule 2), although Z, earlier in the file, also avoids both (rule 3 would pick Z).
    text = """
n_uavs: 4
default: P
topologies:
  P: [[1, 2], [2, 3], [3, 4], [1, 4], [1, 3]]
  X: [[1, 3], [1, 4], [2, 3], [3, 4]]
  Z: [[1, 3], [2, 3], [2, 4]]
  Y: [[1, 3], [1, 4], [2, 3], [2, 4]]
switching:
  - {lost: [1, 2], topology: X}
  - {lost: [3, 4], topology: Y}
"""
    path = tmp_path / "custom.yaml"
    path.write_text(text)
    s = Table2Switcher(load_topology_table(path), n_agents=4)
    assert s.next_topology("P", [(0, 1)]) == "X"
    assert s.next_topology("P", [(0, 1), (2, 3)]) == "Y"
    # 2-4 lost is not in the table: P does not use it, so P stays
    assert s.next_topology("P", [(1, 3)]) == "P"
    # 1-3 lost: no table row, every topology uses it -> general rule
    assert s.next_topology("P", [(0, 2)]) is None
    # rule 3: from the general rule with only 1-2 lost, first intact topology in file order
    assert s.next_topology(None, [(0, 1)]) == "X"


def test_switch_fallback_uses_auto_links_and_reports_components():
    s = Table2Switcher(n_agents=5)
    # UAV 5 far away from the other four
    xy = np.array([[[0, 0], [3000, 0], [0, 3000], [3000, 3000], [80_000, 0]]], dtype=float)
    avail = in_range(xy, R)
    out = s.switch(s.initial(1), avail, xy)
    assert out.topology[0] == AUTO
    assert not out.connected[0] and out.n_components[0] == 2
    assert not out.links[0, 4].any()
    assert bfs_closure(out.links[0])[0, :4].all()


def test_table2_wrong_swarm_size():
    with pytest.raises(ConfigError, match=r"comms\.topology"):
        Table2Switcher(n_agents=6)


@pytest.mark.parametrize(
    ("patch", "field"),
    [
        ({"n_uavs": 1}, "n_uavs"),
        ({"extra": 1}, "extra"),
        ({"default": "Z"}, "default"),
        ({"topologies": {"A": [[1, 2], [3, 4]]}}, "topologies.A"),  # disconnected
        ({"topologies": {"A": [[1, 9]]}}, "topologies.A[0]"),
        ({"switching": [{"lost": [1, 2], "topology": "Q"}]}, "topology"),
    ],
)
def test_bad_topology_file_is_a_config_error(tmp_path, patch, field):
    import yaml

    data = yaml.safe_load(TABLE2_PATH.read_text())
    data.update(patch)
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(ConfigError) as err:
        load_topology_table(path)
    assert field in err.value.field


def test_switcher_table_entry_must_avoid_its_link(tmp_path):
    import yaml

    data = yaml.safe_load(TABLE2_PATH.read_text())
    data["switching"][0] = {"lost": [1, 2], "topology": "D"}  # D uses 1-2
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(ConfigError, match="without the lost link"):
        load_topology_table(path)
    with pytest.raises(ConfigError, match="topology_file"):
        load_topology_table(tmp_path / "missing.yaml")


# ------------------------------------------------------------------ auto rule


def test_auto_connected_iff_in_range_graph_connected():
    rng = np.random.default_rng(42)
    n_envs, n = 200, 8
    xy = random_swarm(rng, n_envs, n, 20_000)
    active = rng.random((n_envs, n)) > 0.15
    avail = link_failures(in_range(xy, R, active), 0.1, rng)
    out = auto_topology(avail, xy, active)
    want = np.array([bfs_connected(a, m) for a, m in zip(avail, active)])
    assert 20 < want.sum() < n_envs - 20  # both cases are exercised
    np.testing.assert_array_equal(out.connected, want)
    links = out.links
    np.testing.assert_array_equal(links, np.swapaxes(links, 1, 2))
    assert not (links & ~avail).any()  # only available links are used
    for e in range(n_envs):
        # same components as the available graph
        np.testing.assert_array_equal(bfs_closure(links[e]), bfs_closure(avail[e]))
    n_comp, _ = connected_components(avail, active)
    np.testing.assert_array_equal(out.n_components, n_comp)
    # two-neighbour rule on the topology wherever the in-range graph allows it
    deg_av = avail.sum(-1)
    deg = links.sum(-1)
    assert np.all(deg >= np.minimum(deg_av, 2))


def test_auto_uses_shortest_links():
    # a tight triangle and one UAV further out: the spanning tree takes the shortest bridge
    xy = np.array([[[0, 0], [1000, 0], [0, 1000], [5000, 0]]], dtype=float)
    avail = in_range(xy, R)
    out = auto_topology(avail, xy, min_neighbours=1)
    assert set(adjacency_to_links(out.links[0])) == {(0, 1), (0, 2), (1, 3)}
    assert out.connected[0] and out.n_components[0] == 1


# ------------------------------------------------------------------ failures, closure


def test_link_failures_reproducible_and_symmetric():
    xy = random_swarm(np.random.default_rng(5), 32, 6, 15_000)
    adj = in_range(xy, R)
    a = link_failures(adj, 0.3, np.random.default_rng(11))
    b = link_failures(adj, 0.3, np.random.default_rng(11))
    c = link_failures(adj, 0.3, np.random.default_rng(12))
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    np.testing.assert_array_equal(a, np.swapaxes(a, 1, 2))
    assert not (a & ~adj).any()
    frac = 1 - a.sum() / adj.sum()
    assert 0.2 < frac < 0.4
    np.testing.assert_array_equal(link_failures(adj, 0.0, np.random.default_rng(0)), adj)
    assert not link_failures(adj, 1.0, np.random.default_rng(0)).any()


def test_reachable_equals_bfs_closure():
    rng = np.random.default_rng(9)
    for n in (1, 2, 5, 16):
        xy = random_swarm(rng, 30, n, 40_000)
        adj = link_failures(in_range(xy, R), 0.2, rng)
        r = reachable(adj)
        want = np.stack([bfs_closure(a) for a in adj])
        np.testing.assert_array_equal(r, want)
    # a long chain needs many relays
    chain = np.zeros((1, 16, 16), dtype=bool)
    chain[0, np.arange(15), np.arange(1, 16)] = True
    chain |= np.swapaxes(chain, 1, 2)
    assert reachable(chain).all()
