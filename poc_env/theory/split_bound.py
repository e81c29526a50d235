"""The rule-aware bound without merged airfields: the fleet split into parts (issue 24).

:func:`poc_env.theory.bound.rule_bound` solves its relaxation exactly for at most two distinct
airfields (transit rows): beyond two, ``bound._merge_groups`` merges the later fields into the
second with the smaller transit of the two, a valid but loose relaxation -- a UAV of one field
is credited as if it could take off from whichever of the merged fields is nearer each cell.
On ``large_400`` (three fields, 12 UAVs) the fields far from a blob are credited the near
field's reach (docs/PLANNER.md, "The rule-aware bound with three airfields").

:func:`split_rule_bound` is the least of these valid upper bounds of the same quantity (the
POS of any fleet keeping the plan rules, the environment's detection model):

* ``rule_bound`` with each field first in the fleet's order (the merge differs);
* for each partition of the fields into blocks of at most two, and for the partition into
  single fields, the sum over the blocks of ``rule_bound`` of the block's UAVs alone (exact
  where ``rule_bound`` is: on grids of more than ``sqrt(bound._MAX_PAIRS)`` cells it merges
  two fields into one too, and then the single fields' sum is the tighter).

*Why the sum is an upper bound.* Any fleet's efforts split by field as ``x = sum_b x_b``,
``x_b`` in block ``b``'s feasible set (``rule_bound``'s polymatroid for its UAVs). The objective
``phi(x) = sum_j m_j POD(x_j / a_j)`` is separable and concave in each ``x_j >= 0`` with
``phi(0) = 0``, so it is subadditive: ``phi(x) <= sum_b phi(x_b) <= sum_b max phi over b's set``.
With at most two fields on a grid where ``rule_bound`` is exact, :func:`split_rule_bound` is
``rule_bound`` itself.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from poc_env.config import Scenario
from poc_env.theory import bound as _bound
from poc_env.theory.bound import rule_bound
from poc_env.theory.probability_map import Grid

#: most partitions of the fields into blocks of at most two that are tried.
MAX_PARTITIONS = 32


@dataclass(frozen=True)
class SplitBound:
    """``upper``: the least bound; ``rule``: ``rule_bound``'s; ``how``: which gave ``upper``
    (``"rule"``, ``"first=F"`` or ``"blocks=(F, F)+(F,)"``, ``F`` field indices in order of
    first appearance in the fleet)."""

    upper: float
    rule: float
    how: str


def _pairings(items: list[int]) -> list[list[tuple[int, ...]]]:
    """Partitions of ``items`` into pairs (and one single when odd), in a fixed order."""
    if len(items) <= 1:
        return [[tuple(items)]] if items else [[]]
    first, rest = items[0], items[1:]
    out: list[list[tuple[int, ...]]] = []
    if len(items) % 2:  # first may be the single
        out += [[(first,), *p] for p in _pairings(rest)]
    for i, other in enumerate(rest):
        left = rest[:i] + rest[i + 1 :]
        if len(left) % 2 and len(items) % 2 == 0:
            continue
        out += [[(first, other), *p] for p in _pairings(left)]
    return [p for p in out if sum(len(b) == 1 for b in p) <= len(items) % 2]


def split_rule_bound(scenario: Scenario, prior) -> SplitBound:
    """The least of the valid rule-aware bounds of the module docstring for ``scenario``'s
    fleet on ``prior``."""
    full = float(rule_bound(scenario, prior).upper)
    groups = list(scenario.fleet)
    lim_to = np.asarray(scenario.takeoff_m, dtype=float).reshape(-1, 2)
    lim_la = np.asarray(scenario.landing_m, dtype=float).reshape(-1, 2)
    # the field (take-off, landing) of each fleet group, in order of first appearance
    keys: list[tuple] = []
    field_of: list[int] = []
    k = 0
    for g in groups:
        key = (tuple(np.round(lim_to[k], 3)), tuple(np.round(lim_la[k], 3)))
        if key not in keys:
            keys.append(key)
        field_of.append(keys.index(key))
        k += g.count
    n = len(keys)
    cells = Grid.from_config(scenario.map).nx * Grid.from_config(scenario.map).ny
    exact_pairs = cells**2 <= _bound._MAX_PAIRS
    if n == 1 or (n == 2 and exact_pairs):
        return SplitBound(full, full, "rule")

    def sub(fields: tuple[int, ...]) -> Scenario:
        fleet = tuple(g for f in fields for g, fo in zip(groups, field_of, strict=True) if fo == f)
        return dataclasses.replace(scenario, fleet=fleet)

    best, how = full, "rule"
    for f in range(n):
        order = (f, *(x for x in range(n) if x != f))
        val = float(rule_bound(sub(order), prior).upper)
        if val < best:
            best, how = val, f"first={f}"
    cache: dict[tuple[int, ...], float] = {}
    singles: list[tuple[int, ...]] = [(f,) for f in range(n)]
    parts = [*_pairings(list(range(n)))[:MAX_PARTITIONS], singles]
    for part in parts:
        total = 0.0
        for block in part:
            if block not in cache:
                cache[block] = float(rule_bound(sub(block), prior).upper)
            total += cache[block]
        if total < best:
            best, how = total, "blocks=" + "+".join(str(b) for b in part)
    return SplitBound(best, full, how)
