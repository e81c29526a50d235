"""Learned re-planning decisions for moving targets (issue 28): which re-plan to fly, and when.

``spacetime_receding`` (:mod:`poc_env.agents.policies.moving`) makes one decision every
``replan_min`` minutes: keep the routes being flown, or fly the default re-plan if the planner's
model scores it ``switch_margin`` above them. :class:`ReplanChoicePolicy` makes the same kind of
decision at the times ``decide_min``, over a wider set of candidates (:func:`candidates`):

* ``keep``: every UAV keeps its route;
* ``replan``: the default re-plan (:func:`poc_env.agents.planning.spacetime.replan`, the
  planner's options of ``spacetime_receding``) for every UAV still searching;
* ``replan_<variant>``: the re-plan with other allocation options (:data:`VARIANTS`);
* ``mix_<mask>``: the default re-plan for a subset of the UAVs (``mask``: one letter per
  re-planned UAV, ``1`` switches, ``0`` keeps), the others keep their routes.

and picks one with a *chooser*:

``rule``
    ``spacetime_receding``'s rule (the default re-plan if it scores ``switch_margin`` above
    ``keep`` in the planner's model, else ``keep``); with ``decide_min=(20,)`` this policy flies
    exactly what ``spacetime_receding`` flies (``tests/policies/test_replan_choice.py``).
``best``
    the candidate the planner's model scores highest, if ``switch_margin`` above ``keep``
    (a re-tuned constant rule).
``oracle``
    a lookahead: flies each candidate from a copy of the environment (:func:`copy.deepcopy` of
    the env and this policy together) to the episode's end, later decisions by ``rule`` at
    ``spacetime_receding``'s times, and picks the candidate of highest flown POSC (eq. 13).
    POSC is the belief's cumulative POS, a deterministic function of the flown paths (the
    hidden target only decides ``detected``), so the rollout reads nothing the planner could
    not compute; it is the upper bound a chooser of these candidates can reach with ``rule``
    after it.
``model``
    a fitted :class:`ChooserModel` (a JSON checkpoint): predicts each candidate's flown gain
    over ``keep`` from its :func:`features` and flies the highest prediction if above 0.

Every choice records the decision (time, candidates, planner scores, features, and for the
oracle the flown POSC of each candidate) in ``self.decisions``: the training data of the chooser
(``results/drift_replan/collect.py``).
"""

from __future__ import annotations

import copy
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from poc_env.agents.planning.spacetime import airborne_poc, choose_routes, replan
from poc_env.agents.policies.moving import SWITCH_MARGIN, SpacetimeRecedingPolicy, drift_of
from poc_env.errors import ConfigError
from poc_env.sim.autopilot import must_return
from poc_env.sim.observations import decode_vector, split_observation

#: the re-plans other than the default one: name -> allocation options replacing the default's.
VARIANTS: dict[str, dict[str, Any]] = {
    "levels3": {"levels": (3,)},
    "levels6": {"levels": (6,)},
    "margin08": {"margin": 0.8},
    "margin06": {"margin": 0.6},
}

#: the candidate kinds, in the order of the one-hot in :func:`features` (``keep`` has none).
KINDS = ("replan", *(f"replan_{v}" for v in VARIANTS), "mix1", "mix2")

#: names of :func:`features`' columns.
FEATURES = (
    "gain_model",  # planner-model POS of the candidate minus keep's
    "gain_model_rel",  # the same over keep's
    "keep_model",  # planner-model POS of keep
    "time",  # decision time / endurance
    "drift",  # drift speed / search speed
    "drift_along",  # cosine between the drift and the way from the fleet to the mass
    "spread",  # belief's standard distance / map diagonal
    "mass",  # mass left in the map (the belief's sum)
    "searching",  # UAVs re-planned / fleet size
    "switched",  # share of those UAVs the candidate gives a new route
    "gain_x_time",
    "gain_x_drift",
    "turn",  # mean turn to the first waypoint (/ pi), the candidate's minus keep's
    "lead",  # mean distance to the first waypoint / map diagonal, minus keep's
    "length",  # mean route length / (line speed x usable time left), minus keep's
    *(f"kind_{k}" for k in KINDS),
)


@dataclass
class Candidate:
    """One set of routes to fly from a decision: per UAV of ``ks`` its remaining ground
    waypoints and leg speeds; ``new[j]`` says whether UAV ``ks[j]`` gets a new route."""

    name: str
    kind: str
    routes: list
    speeds: list
    new: list[bool]
    plan_speeds: dict


def _kept(follower: Any, ks: list[int]) -> tuple[list, list]:
    """The routes being flown by ``ks`` from where each UAV is, at the follower's speeds."""
    kept, kept_v = [], []
    for k in ks:
        i = int(follower.index[k])
        kept.append(follower.waypoints[k][i:])
        kept_v.append(
            [follower.transit_speed if i == 0 else follower.pattern_speed]
            + [follower.pattern_speed] * (len(follower.waypoints[k]) - i)
        )
    return kept, kept_v


def _route_key(c: Candidate) -> bytes:
    """Bytes that differ between candidates that fly differently."""
    parts = [np.asarray(c.new, dtype=bool).tobytes()]
    for r, v in zip(c.routes, c.speeds, strict=True):
        parts += [np.asarray(r, dtype=float).tobytes(), b"|", np.asarray(v, dtype=float).tobytes()]
    parts.append(json.dumps(c.plan_speeds, sort_keys=True).encode())
    return b"#".join(parts)


def _plan_routes(plan: dict, n: int, follower: Any) -> tuple[list, list, dict]:
    v = plan.get("speeds_mps") or {}
    new = [np.asarray(plan["uavs"][j]["waypoints_m"], dtype=float).reshape(-1, 2) for j in range(n)]
    new_v = [
        [v.get("out", follower.transit_speed)] + [v.get("line", follower.pattern_speed)] * len(w)
        for w in new
    ]
    return new, new_v, v


def geometry(
    cand: Candidate, xy: np.ndarray, heading: np.ndarray, diag_m: float, reach_m: float
) -> np.ndarray:
    """``(turn, lead, length)`` of a candidate's routes, means over its UAVs: the heading
    change to the first waypoint (/ pi), the distance to it (/ ``diag_m``) and the route's
    length from the UAV (/ ``reach_m``, the distance the endurance left flies)."""
    out = np.zeros(3)
    n = len(cand.routes)
    for j, r in enumerate(cand.routes):
        r = np.asarray(r, dtype=float).reshape(-1, 2)
        if not len(r):
            continue
        d = r[0] - xy[j]
        turn = np.angle(np.exp(1j * (math.atan2(d[1], d[0]) - float(heading[j]))))
        path = np.vstack([xy[j], r])
        length = float(np.hypot(*np.diff(path, axis=0).T).sum())
        out += (abs(turn) / math.pi, float(np.hypot(*d)) / diag_m, length / max(reach_m, 1.0))
    return out / max(n, 1)


def features(
    scores: list[float],
    cands: list[Candidate],
    ctx: dict[str, float],
    geo: list[np.ndarray] | None = None,
) -> np.ndarray:
    """``(len(cands) - 1, len(FEATURES))``: the features of every candidate but ``keep``
    (candidate 0), from the planner-model ``scores``, the decision's context ``ctx``
    (:meth:`ReplanChoicePolicy.context`) and each candidate's :func:`geometry` (``geo``,
    zeros if None)."""
    keep = float(scores[0])
    geo = [np.zeros(3)] * len(cands) if geo is None else geo
    rows = []
    for c, s, gm in zip(cands[1:], scores[1:], geo[1:], strict=True):
        g = float(s) - keep
        kind = [1.0 if c.kind == k else 0.0 for k in KINDS]
        rows.append(
            [
                g,
                g / max(keep, 1e-6),
                keep,
                ctx["time"],
                ctx["drift"],
                ctx["drift_along"],
                ctx["spread"],
                ctx["mass"],
                ctx["searching"],
                float(np.mean(c.new)),
                g * ctx["time"],
                g * ctx["drift"],
                *(np.asarray(gm) - np.asarray(geo[0])),
                *kind,
            ]
        )
    return np.asarray(rows, dtype=float).reshape(-1, len(FEATURES))


#: the continuous features :func:`expand` multiplies pairwise (``"quadratic"``).
CONTINUOUS = (
    "gain_model",
    "keep_model",
    "time",
    "drift",
    "drift_along",
    "spread",
    "mass",
    "searching",
    "switched",
    "turn",
    "lead",
    "length",
)

#: the feature expansions a :class:`ChooserModel` may use (:func:`expand`).
EXPANSIONS = ("linear", "kinds", "quadratic")


def expand(x: np.ndarray, how: str) -> np.ndarray:
    """The model's inputs from :func:`features`' rows: ``"linear"`` as they are; ``"kinds"``
    adds the planner-model gain times each candidate kind (a slope per kind);
    ``"quadratic"`` adds those and every product of two :data:`CONTINUOUS` features."""
    if how not in EXPANSIONS:
        raise ConfigError("expand", how, f"one of {', '.join(EXPANSIONS)}")
    x = np.asarray(x, dtype=float).reshape(-1, len(FEATURES))
    cols = [x]
    if how in ("kinds", "quadratic"):
        g = x[:, FEATURES.index("gain_model")]
        kinds = x[:, [FEATURES.index(f"kind_{k}") for k in KINDS]]
        cols.append(g[:, None] * kinds)
    if how == "quadratic":
        c = x[:, [FEATURES.index(f) for f in CONTINUOUS]]
        i, j = np.triu_indices(c.shape[1])
        cols.append(c[:, i] * c[:, j])
    return np.hstack(cols)


@dataclass
class ChooserModel:
    """Ridge regression of a candidate's flown gain over ``keep`` on its standardised,
    expanded :func:`features` (``meta["expand"]``, :func:`expand`): ``gain = (z - mean) /
    scale @ weights + bias``. Saved as JSON (no pickle): :meth:`save`, :meth:`load`."""

    mean: np.ndarray
    scale: np.ndarray
    weights: np.ndarray
    bias: float
    meta: dict

    def predict(self, x: np.ndarray) -> np.ndarray:
        z = expand(x, self.meta.get("expand", "linear"))
        return ((z - self.mean) / self.scale) @ self.weights + self.bias

    @classmethod
    def fit(
        cls,
        x: np.ndarray,
        y: np.ndarray,
        ridge: float,
        how: str = "linear",
        meta: dict | None = None,
    ) -> ChooserModel:
        """Fit on :func:`features`' rows ``x`` and the flown gains ``y``."""
        z = expand(x, how)
        y = np.asarray(y, dtype=float)
        mean = z.mean(axis=0)
        scale = z.std(axis=0)
        scale[scale < 1e-12] = 1.0
        zs = (z - mean) / scale
        bias = float(y.mean())
        a = zs.T @ zs + ridge * len(zs) * np.eye(zs.shape[1])
        w = np.linalg.solve(a, zs.T @ (y - bias))
        return cls(mean, scale, w, bias, dict(meta or {}, ridge=ridge, expand=how))

    def to_dict(self) -> dict:
        return {
            "features": list(FEATURES),
            "mean": self.mean.tolist(),
            "scale": self.scale.tolist(),
            "weights": self.weights.tolist(),
            "bias": self.bias,
            "meta": self.meta,
        }

    def save(self, path: str | Path) -> Path:
        from poc_env.io import write_text_atomic

        return write_text_atomic(Path(path), json.dumps(self.to_dict(), indent=1) + "\n")

    @classmethod
    def load(cls, path: str | Path) -> ChooserModel:
        p = Path(path)
        if not p.is_file():
            raise ConfigError("path", str(path), "a chooser model file (.json)")
        d = json.loads(p.read_text())
        if list(d.get("features", [])) != list(FEATURES):
            raise ConfigError(
                "path", str(path), f"a chooser model over the features {', '.join(FEATURES)}"
            )
        return cls(
            np.asarray(d["mean"], dtype=float),
            np.asarray(d["scale"], dtype=float),
            np.asarray(d["weights"], dtype=float),
            float(d["bias"]),
            dict(d.get("meta", {})),
        )


CHOOSERS = ("rule", "best", "oracle", "keep", "switch", "model")


class ReplanChoicePolicy(SpacetimeRecedingPolicy):
    """The re-planning decisions of ``spacetime_receding`` made by a chooser (module
    docstring). ``chooser``: one of :data:`CHOOSERS` (``model`` needs ``model_path``);
    ``decide_min``: decision times (minutes); ``rule_min``: the decision times of the ``rule``
    that flies after an oracle's decision in its rollouts (``spacetime_receding``'s)."""

    name = "receding_choice"

    def __init__(
        self,
        chooser: str = "rule",
        model_path: str | None = None,
        decide_min: tuple[float, ...] = (20.0,),
        rule_min: tuple[float, ...] = (20.0,),
        model_min: tuple[float, ...] | None = None,
        lookahead: int = 0,
        variants: bool = True,
        switch_margin: float = SWITCH_MARGIN,
        **kwargs: Any,
    ) -> None:
        super().__init__(switch_margin=switch_margin, **kwargs)
        if chooser not in CHOOSERS:
            raise ConfigError("chooser", chooser, f"one of {', '.join(CHOOSERS)}")
        self.chooser = chooser
        self.model = None
        if chooser == "model":
            if model_path is None:
                raise ConfigError("model_path", model_path, "a chooser model file (.json)")
            self.model = ChooserModel.load(model_path)
        for field, times in (("decide_min", decide_min), ("rule_min", rule_min)):
            if not times or not all(
                isinstance(t, int | float) and 0.0 < float(t) <= 1e4 for t in times
            ):
                raise ConfigError(field, times, "decision times in minutes, in (0, 1e4]")
        self.decide_s = tuple(sorted(float(t) * 60.0 for t in decide_min))
        self.rule_s = tuple(sorted(float(t) * 60.0 for t in rule_min))
        if model_min is None and self.model is not None:
            model_min = tuple(self.model.meta.get("model_min", decide_min))
        #: the decision times (s) at which the model chooses; ``rule`` decides at the others
        self.model_s = tuple(float(t) * 60.0 for t in (model_min or decide_min))
        self.variants = bool(variants)
        if not (isinstance(lookahead, int) and 0 <= lookahead <= 64):
            raise ConfigError("lookahead", lookahead, "a number of candidates in [0, 64]")
        if lookahead and chooser not in ("best", "model"):
            raise ConfigError("lookahead", lookahead, "0 unless the chooser is best or a model")
        #: > 0: roll out keep and the chooser's ``lookahead`` best-ranked candidates (by the
        #: planner's model for ``best``, by the model's prediction for a model) and fly the one
        #: of highest flown POSC, as the oracle does over every candidate
        self.lookahead = lookahead
        self.record = True

    def reset(self, env: Any, seed: int) -> None:
        super().reset(env, seed)
        self.todo = list(self.decide_s)
        self.decisions: list[dict] = []

    # -- a decision ----------------------------------------------------------------------
    def searching(self, observations: dict) -> tuple[list[int], np.ndarray]:
        """The UAVs a re-plan may route (live, not heading home, route not finished) and
        their positions (metres)."""
        p = self.params
        ks, pos, head = [], [], []
        for k, agent in enumerate(self.agents):
            if agent not in observations:
                continue
            q = decode_vector(p, split_observation(observations[agent], p.grid.shape)[1])
            if must_return(p, q, k) or self.follower.index[k] >= len(self.follower.waypoints[k]):
                continue
            ks.append(k)
            pos.append(np.asarray(q["xy"], dtype=float))
            head.append(float(q["heading"]))
        self.headings = np.array(head)
        return ks, np.array(pos).reshape(-1, 2)

    def context(self, belief: np.ndarray, xy: np.ndarray, now: float, n_ks: int) -> dict:
        """The decision's context features (:func:`features`)."""
        sc, p = self.env.scenario, self.params
        grid = p.grid
        coarse = grid.coarsen(belief, p.s)
        mass = float(coarse.sum())
        ys, xs = np.indices(coarse.shape)
        cx = (xs + 0.5) * grid.cell_m
        cy = (ys + 0.5) * grid.cell_m
        w = coarse / mass if mass > 0 else np.full(coarse.shape, 1.0 / coarse.size)
        mx, my = float((w * cx).sum()), float((w * cy).sum())
        spread = math.sqrt(float((w * ((cx - mx) ** 2 + (cy - my) ** 2)).sum()))
        diag = math.hypot(coarse.shape[1] * grid.cell_m, coarse.shape[0] * grid.cell_m)
        drift = drift_of(self.env)
        to_mass = np.array([mx, my]) - xy.mean(axis=0)
        nd, nm = float(np.hypot(*drift)), float(np.hypot(*to_mass))
        along = float(drift @ to_mass) / (nd * nm) if nd > 1e-9 and nm > 1e-9 else 0.0
        return {
            "time": now / sc.uav.endurance_s,
            "drift": nd / sc.uav.search_speed_mps,
            "drift_along": along,
            "spread": spread / diag,
            "mass": mass,
            "searching": n_ks / len(self.agents),
        }

    def candidates(self, ks: list[int], xy: np.ndarray, now: float, belief, poc) -> list:
        """keep, the default re-plan, and (if ``variants``) the other re-plans and mixes."""
        sc, p, drift = self.env.scenario, self.params, drift_of(self.env)
        old = self.follower
        kept, kept_v = _kept(old, ks)
        n = len(ks)
        out = [Candidate("keep", "keep", kept, kept_v, [False] * n, {})]
        seed = self.seed + self.plans
        self.plans += 1
        plan = replan(sc, belief, drift, p.s, xy, now, ks, seed=seed, poc=poc, **self.alloc)
        new, new_v, v = _plan_routes(plan, n, old)
        out.append(Candidate("replan", "replan", new, new_v, [True] * n, v))
        if not self.variants or self._chooser(now) == "rule":
            return out
        for name, opts in VARIANTS.items():
            alloc = {**self.alloc, **opts}
            pl = replan(sc, belief, drift, p.s, xy, now, ks, seed=seed, poc=poc, **alloc)
            r, rv, vv = _plan_routes(pl, n, old)
            out.append(Candidate(f"replan_{name}", f"replan_{name}", r, rv, [True] * n, vv))
        if n > 1:
            for mask in range(1, 2**n - 1):
                bits = [bool(mask >> j & 1) for j in range(n)]
                r = [new[j] if bits[j] else kept[j] for j in range(n)]
                rv = [new_v[j] if bits[j] else kept_v[j] for j in range(n)]
                label = "".join("1" if b else "0" for b in bits)
                kind = "mix1" if sum(bits) == 1 else "mix2"
                out.append(Candidate(f"mix_{label}", kind, r, rv, bits, v))
        return out

    def apply(self, cand: Candidate, ks: list[int]) -> None:
        """Fly ``cand``: the UAVs it gives a new route fly it from now, the others keep theirs."""
        if not any(cand.new):
            return
        self.switches += 1
        old = self.follower
        wps: list = [np.zeros((0, 2))] * len(self.agents)
        for j, k in enumerate(ks):
            if cand.new[j]:
                wps[k] = cand.routes[j]
        self._fly(wps, {"speeds_mps": cand.plan_speeds})
        for j, k in enumerate(ks):  # UAVs kept: their route and progress as they were
            if not cand.new[j]:
                self.follower.waypoints[k] = old.waypoints[k]
                self.follower.index[k] = old.index[k]
        for k in range(len(self.agents)):
            if k not in ks:
                self.follower.waypoints[k] = old.waypoints[k]
                self.follower.index[k] = old.index[k]

    def rollout(self, observations: dict, cand: Candidate, ks: list[int], now: float) -> float:
        """The POSC at the episode's end if ``cand`` is flown now and ``rule`` decides after,
        flown on a deep copy of the environment and this policy (the live ones are untouched)."""
        env, pol = copy.deepcopy((self.env, self))
        pol.record = False
        pol.chooser = "rule"
        pol.todo = [t for t in self.rule_s if t > now + 1e-9]
        pol.apply(cand, ks)
        obs = copy.deepcopy(observations)
        actions, _ = pol.follower.predict(obs)
        while env.agents:
            obs, *_ = env.step(actions)
            if not env.agents:
                break
            actions, _ = pol.predict(obs)
        return float(env.sim_state.posc[0])

    def decide(self, observations: dict, now: float) -> None:
        ks, xy = self.searching(observations)
        sc = self.env.scenario
        if not ks or sc.uav.endurance_s - now < 0.2 * sc.uav.endurance_s:
            return
        p, drift = self.params, drift_of(self.env)
        belief = np.array(self.env.sim_state.belief[0], dtype=float)
        poc = airborne_poc(sc, belief, drift, p.s, xy, now, ks)
        cands = self.candidates(ks, xy, now, belief, poc)
        pick, scores = choose_routes(
            sc,
            belief,
            drift,
            p.s,
            xy,
            now,
            ks,
            [(c.routes, c.speeds) for c in cands],
            self.margin,
            poc=poc,
        )
        self.scores.append(scores)
        ctx = self.context(belief, xy, now, len(ks))
        grid = p.grid
        diag = math.hypot(grid.shape[1] * grid.cell_m, grid.shape[0] * grid.cell_m)
        left = sc.uav.usable_fraction * sc.uav.endurance_s - now
        reach = sc.uav.search_speed_mps * max(left, 0.0)
        geo = [geometry(c, xy, self.headings, diag, reach) for c in cands]
        x = features(scores, cands, ctx, geo)
        flown: list[float | None] | None = None
        chooser = self._chooser(now)
        if chooser in ("best", "model") and self.lookahead and len(cands) > 1:
            if chooser == "best":
                rank = np.asarray(scores[1:], dtype=float)
            else:
                assert self.model is not None
                rank = self.model.predict(x)
            got = {0: self.rollout(observations, cands[0], ks, now)}
            keys = {_route_key(cands[0])}
            for j in np.argsort(-rank, kind="stable"):  # best-ranked first, distinct routes
                key = _route_key(cands[int(j) + 1])
                if key in keys:
                    continue
                if len(keys) > self.lookahead:
                    break
                keys.add(key)
                got[int(j) + 1] = self.rollout(observations, cands[int(j) + 1], ks, now)
            flown = [got.get(k) for k in range(len(cands))]
            i = max(got, key=lambda k: (got[k], -k))
        elif chooser == "rule":
            i = 1 if scores[1] > scores[0] + self.margin else 0
        elif chooser == "best":
            i = pick
        elif chooser == "keep":
            i = 0
        elif chooser == "switch":
            i = 1
        elif chooser == "oracle":
            seen: dict[bytes, float] = {}
            for c in cands:  # candidates with the same routes fly the same (one rollout)
                key = _route_key(c)
                if key not in seen:
                    seen[key] = self.rollout(observations, c, ks, now)
            values = [seen[_route_key(c)] for c in cands]
            flown = list(values)
            i = int(np.argmax(values))  # ties: the first (keep before any switch)
        else:
            assert self.model is not None
            pred = self.model.predict(x) if len(x) else np.zeros(0)
            j = int(np.argmax(pred)) if len(pred) else -1
            i = j + 1 if j >= 0 and pred[j] > 0.0 else 0
        if self.record:
            self.decisions.append(
                {
                    "time_s": now,
                    "ks": list(ks),
                    "names": [c.name for c in cands],
                    "scores": [float(s) for s in scores],
                    "features": x.tolist(),
                    "flown": flown,
                    "pick": i,
                }
            )
        self.apply(cands[i], ks)

    def _chooser(self, now: float) -> str:
        """The chooser of the decision at ``now``: a model chooses at its own times only."""
        if self.chooser == "model" and not any(abs(now - t) < 1e-6 for t in self.model_s):
            return "rule"
        return self.chooser

    def predict(self, observations: dict, state=None, episode_start=None, deterministic=True):
        now = float(self.env.sim_state.step[0]) * self.params.dt
        if self.todo and now >= self.todo[0] - 1e-9:
            while self.todo and now >= self.todo[0] - 1e-9:
                self.todo.pop(0)
            self.decide(observations, now)
        return self.follower.predict(observations, state)


#: the folder of shipped chooser models (package data): ``receding_choice:NAME`` finds
#: ``agents/checkpoints/choosers/NAME.json``.
def shipped_choosers() -> list[str]:
    """The names of the shipped chooser models."""
    import importlib.resources

    folder = importlib.resources.files("poc_env.agents").joinpath("checkpoints", "choosers")
    if not folder.is_dir():
        return []
    return sorted(f.name[:-5] for f in folder.iterdir() if f.name.endswith(".json"))


def _minutes(field: str, text: str) -> tuple[float, ...]:
    try:
        return tuple(float(t) for t in text.split("-") if t)
    except ValueError:
        raise ConfigError(
            field, text, "decision times in minutes joined by '-' (10-20-30)"
        ) from None


def from_spec(spec: str, **kwargs: Any) -> ReplanChoicePolicy:
    """The policy of ``receding_choice:SPEC``: ``SPEC`` is a chooser of :data:`CHOOSERS` other
    than ``model``, optionally with its decision times (``oracle@10-20-30``), or a chooser
    model: a ``.json`` path or the name of a shipped one (:func:`shipped_choosers`), flown at
    the decision times recorded in it. ``*K`` after ``best`` or a model rolls out ``keep`` and
    its ``K`` best-ranked candidates and flies the best of them (``best*2@10-20``)."""
    if not isinstance(spec, str) or not spec:
        raise ConfigError("spec", spec, "a chooser or a chooser model")
    head, _, times = spec.partition("@")
    head, star, k = head.partition("*")
    if star:
        if not k.isdigit():
            raise ConfigError("spec", spec, "NAME*K with K the candidates rolled out (best*2)")
        kwargs = {**kwargs, "lookahead": int(k)}
    if head in CHOOSERS and head != "model":
        decide = _minutes("spec", times) if times else (20.0,)
        return ReplanChoicePolicy(head, decide_min=decide, **kwargs)
    path: str | Path = head
    if head in shipped_choosers():
        import importlib.resources

        ref = importlib.resources.files("poc_env.agents").joinpath(
            "checkpoints", "choosers", f"{head}.json"
        )
        path = str(ref)
    elif not head.endswith(".json"):
        raise ConfigError(
            "spec",
            spec,
            f"one of {', '.join(c for c in CHOOSERS if c != 'model')} (@T-T-...), a chooser "
            f"model .json or a shipped one ({', '.join(shipped_choosers()) or 'none'})",
        )
    model = ChooserModel.load(path)
    decide = tuple(float(t) for t in model.meta.get("decide_min", (20.0,)))
    if times:
        decide = _minutes("spec", times)
    return ReplanChoicePolicy("model", str(path), decide_min=decide, **kwargs)
