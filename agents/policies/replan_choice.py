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
    With ``horizon_min`` (``oracle~H``) the rollouts stop ``H`` minutes after the decision
    and score the POSC then, plus, with ``value_path`` (``oracle~H+VALUE.json``), a
    :class:`ValueModel`'s estimate of the POSC still to come from the state reached (its
    :data:`STATE_FEATURES`): a shorter lookahead ended by a learned value.
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
from typing import Any, ClassVar

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

    #: the names of the input columns (checked on :meth:`load`)
    COLUMNS: ClassVar[tuple[str, ...]] = FEATURES

    @staticmethod
    def expand(x: np.ndarray, how: str) -> np.ndarray:
        return expand(x, how)

    def predict(self, x: np.ndarray) -> np.ndarray:
        z = self.expand(x, self.meta.get("expand", "linear"))
        return ((z - self.mean) / self.scale) @ self.weights + self.bias

    @classmethod
    def fit(
        cls,
        x: np.ndarray,
        y: np.ndarray,
        ridge: float,
        how: str = "linear",
        meta: dict | None = None,
        groups: np.ndarray | None = None,
    ) -> Any:
        """Fit on :func:`features`' rows ``x`` and the flown gains ``y``. ``groups`` (one
        label per row): fit the slopes on the deviations from each group's mean only (what
        ranks the rows of one group), the bias then on the level."""
        z = cls.expand(x, how)
        y = np.asarray(y, dtype=float)
        mean = z.mean(axis=0)
        scale = z.std(axis=0)
        scale[scale < 1e-12] = 1.0
        zs = (z - mean) / scale
        bias = float(y.mean())
        yc = y - bias
        if groups is not None:  # within-group deviations only (fixed effects): the slopes
            g = np.unique(np.asarray(groups), return_inverse=True)[1]  # that rank a group
            counts = np.bincount(g)[:, None]
            zs = zs - (np.stack([np.bincount(g, weights=c) for c in zs.T], 1) / counts)[g]
            yc = yc - (np.bincount(g, weights=yc) / counts[:, 0])[g]
        a = zs.T @ zs + ridge * len(zs) * np.eye(zs.shape[1])
        w = np.linalg.solve(a, zs.T @ yc)
        if groups is not None:  # the level: the mean residual
            bias = float(y.mean() - (((z - mean) / scale) @ w).mean())
        meta = dict(meta or {}, ridge=ridge, expand=how, within=groups is not None)
        return cls(mean, scale, w, bias, meta)

    def to_dict(self) -> dict:
        return {
            "features": list(self.COLUMNS),
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
    def load(cls, path: str | Path) -> Any:
        p = Path(path)
        what = "a value model" if cls.COLUMNS is STATE_FEATURES else "a chooser model"
        if not p.is_file():
            raise ConfigError("path", str(path), f"{what} file (.json)")
        try:
            d = json.loads(p.read_text())
        except (UnicodeDecodeError, json.JSONDecodeError) as e:
            raise ConfigError("path", str(path), f"{what} file: JSON ({e})") from None
        if not isinstance(d, dict) or list(d.get("features", [])) != list(cls.COLUMNS):
            raise ConfigError(
                "path", str(path), f"{what} over the features {', '.join(cls.COLUMNS)}"
            )
        meta = d.get("meta", {})
        if not isinstance(meta, dict):
            raise ConfigError(f"{path}: meta", meta, "an object")
        # the width the model's expansion gives (an unknown expansion is refused by it)
        width = cls.expand(np.zeros((1, len(cls.COLUMNS))), meta.get("expand", "linear")).shape[1]
        arrays = []
        for key in ("mean", "scale", "weights"):
            try:
                a = np.asarray(d.get(key), dtype=float)
            except (TypeError, ValueError):
                a = np.empty(0)
            if a.shape != (width,) or not np.all(np.isfinite(a)):
                raise ConfigError(f"{path}: {key}", d.get(key), f"{width} finite numbers")
            arrays.append(a)
        if np.any(arrays[1] <= 0):
            raise ConfigError(f"{path}: scale", d["scale"], "numbers > 0")
        bias = d.get("bias")
        if isinstance(bias, bool) or not isinstance(bias, int | float) or not np.isfinite(bias):
            raise ConfigError(f"{path}: bias", bias, "a finite number")
        return cls(arrays[0], arrays[1], arrays[2], float(bias), dict(meta))


#: names of :meth:`ReplanChoicePolicy.state_features`' columns: the inputs of a
#: :class:`ValueModel` (the POSC still to come from a state, the rule re-planning after).
STATE_FEATURES = (
    "time_left",  # (usable endurance - now) / endurance
    "posc",  # POSC so far (eq. 13)
    "mass",  # mass left in the map (the coarse belief's sum)
    "spread",  # belief's standard distance / map diagonal
    "dist",  # mean distance of the searching UAVs to the belief's centre / map diagonal
    "drift",  # drift speed / search speed
    "drift_along",  # cosine between the drift and the way from the fleet to the mass
    "searching",  # UAVs still searching / fleet size
    "length",  # mean route length left / (search speed x usable time left)
    "keep_model",  # planner-model POS of the routes being flown (choose_routes' score)
)

#: the expansions a :class:`ValueModel` may use: as they are, or with every pairwise product.
VALUE_EXPANSIONS = ("linear", "quadratic")


def expand_state(x: np.ndarray, how: str) -> np.ndarray:
    """A :class:`ValueModel`'s inputs from :data:`STATE_FEATURES` rows
    (:data:`VALUE_EXPANSIONS`)."""
    if how not in VALUE_EXPANSIONS:
        raise ConfigError("expand", how, f"one of {', '.join(VALUE_EXPANSIONS)}")
    x = np.asarray(x, dtype=float).reshape(-1, len(STATE_FEATURES))
    if how == "linear":
        return x
    i, j = np.triu_indices(x.shape[1])
    return np.hstack([x, x[:, i] * x[:, j]])


class ValueModel(ChooserModel):
    """Ridge regression of the POSC still to come (to the episode's end, ``rule`` deciding at
    its times) from a state's :data:`STATE_FEATURES`: the learned value that ends a truncated
    rollout (``receding_choice:oracle~H+VALUE.json``). Same JSON layout as :class:`ChooserModel`."""

    COLUMNS = STATE_FEATURES

    @staticmethod
    def expand(x: np.ndarray, how: str) -> np.ndarray:
        return expand_state(x, how)


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
        horizon_min: float | None = None,
        value_path: str | None = None,
        snap_min: tuple[float, ...] = (),
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
        if horizon_min is not None:
            if not (isinstance(horizon_min, int | float) and 0.0 < float(horizon_min) <= 1e4):
                raise ConfigError("horizon_min", horizon_min, "a rollout length in (0, 1e4] min")
            if chooser != "oracle" and not lookahead:
                raise ConfigError(
                    "horizon_min", horizon_min, "None unless the chooser rolls out (oracle, *K)"
                )
        if value_path is not None and horizon_min is None:
            raise ConfigError("value_path", value_path, "None unless the rollouts are truncated")
        #: rollouts stop ``horizon_s`` after the decision (None: at the episode's end) and
        #: score the POSC then, plus the value model's POSC to come if there is one
        self.horizon_s = None if horizon_min is None else float(horizon_min) * 60.0
        self.value = None if value_path is None else ValueModel.load(value_path)
        #: times (s) at which a rollout records its state's features and POSC (training data)
        self.snap_s = tuple(sorted(float(t) * 60.0 for t in snap_min))
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

    def state_features(self, observations: dict, now: float) -> np.ndarray:
        """The state's :data:`STATE_FEATURES` (a :class:`ValueModel`'s inputs)."""
        sc, p = self.env.scenario, self.params
        ks, xy = self.searching(observations)
        belief = np.array(self.env.sim_state.belief[0], dtype=float)
        grid = p.grid
        diag = math.hypot(grid.shape[1] * grid.cell_m, grid.shape[0] * grid.cell_m)
        left = max(sc.uav.usable_fraction * sc.uav.endurance_s - now, 0.0)
        dist = length = keep = 0.0
        if ks:
            ctx = self.context(belief, xy, now, len(ks))
            coarse = grid.coarsen(belief, p.s)
            mass = float(coarse.sum())
            ys, xs = np.indices(coarse.shape)
            w = coarse / mass if mass > 0 else np.full(coarse.shape, 1.0 / coarse.size)
            centre = (
                np.array([float((w * (xs + 0.5)).sum()), float((w * (ys + 0.5)).sum())])
                * grid.cell_m
            )  # the frame of context()
            dist = float(np.hypot(*(xy - centre).T).mean()) / diag
            kept, kept_v = _kept(self.follower, ks)
            reach = sc.uav.search_speed_mps * max(left, 1.0)
            cand = Candidate("keep", "keep", kept, kept_v, [False] * len(ks), {})
            length = float(geometry(cand, xy, self.headings, diag, reach)[2])
            _, (keep,) = choose_routes(
                sc, belief, drift_of(self.env), p.s, xy, now, ks, [(kept, kept_v)], self.margin
            )
        else:
            ctx = self.context(belief, np.zeros((1, 2)), now, 0)
        return np.array(
            [
                left / sc.uav.endurance_s,
                float(self.env.sim_state.posc[0]),
                ctx["mass"],
                ctx["spread"],
                dist,
                ctx["drift"],
                ctx["drift_along"] if ks else 0.0,
                ctx["searching"],
                length,
                float(keep),
            ]
        )

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
        flown on a deep copy of the environment and this policy (the live ones are untouched).
        With ``horizon_s`` the rollout stops that long after ``now`` (before the policy acts at
        that step): the POSC then, plus the :class:`ValueModel`'s POSC to come if there is one.
        With ``snap_s`` it records ``(time, state features, POSC)`` at those times in
        ``self.snaps`` (the value's training data)."""
        env, pol = copy.deepcopy((self.env, self))
        pol.record = False
        pol.chooser = "rule"
        pol.lookahead = 0
        pol.todo = [t for t in self.rule_s if t > now + 1e-9]
        pol.apply(cand, ks)
        obs = copy.deepcopy(observations)
        stop = math.inf if self.horizon_s is None else now + self.horizon_s
        snaps = [t for t in self.snap_s if t > now + 1e-9]
        self.snaps: list[tuple[float, list[float], float]] = []
        actions, _ = pol.follower.predict(obs)
        while env.agents:
            obs, *_ = env.step(actions)
            if not env.agents:
                break
            t = float(env.sim_state.step[0]) * self.params.dt
            while snaps and t >= snaps[0] - 1e-9:
                snaps.pop(0)
                x = pol.state_features(obs, t)
                self.snaps.append((t, x.tolist(), float(env.sim_state.posc[0])))
            if t >= stop - 1e-9:
                posc = float(env.sim_state.posc[0])
                if self.value is None:
                    return posc
                return posc + float(self.value.predict(pol.state_features(obs, t))[0])
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
        snaps: list | None = None
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
            snapped: dict[bytes, list] = {}
            for c in cands:  # candidates with the same routes fly the same (one rollout)
                key = _route_key(c)
                if key not in seen:
                    seen[key] = self.rollout(observations, c, ks, now)
                    snapped[key] = self.snaps
            values = [seen[_route_key(c)] for c in cands]
            flown = list(values)
            snaps = [snapped[_route_key(c)] for c in cands] if self.snap_s else None
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
                    **({"snaps": snaps} if snaps is not None else {}),
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
    """The decision times of ``text`` (``10-20-30``): each a number, none empty (``-5`` or
    ``10--20`` was read as 5 or 10, 20), none twice (issue 25 audit)."""
    allowed = "distinct decision times in minutes joined by '-' (10-20-30)"
    parts = text.split("-")
    try:
        times = tuple(float(t) for t in parts)
    except ValueError:  # an empty part (a leading, trailing or doubled '-') is one too
        raise ConfigError(field, text, allowed) from None
    if len(set(times)) != len(times):
        raise ConfigError(field, text, allowed)
    return times


def from_spec(spec: str, **kwargs: Any) -> ReplanChoicePolicy:
    """The policy of ``receding_choice:SPEC``: ``SPEC`` is a chooser of :data:`CHOOSERS` other
    than ``model``, optionally with its decision times (``oracle@10-20-30``), or a chooser
    model: a ``.json`` path or the name of a shipped one (:func:`shipped_choosers`), flown at
    the decision times recorded in it. ``*K`` after ``best`` or a model rolls out ``keep`` and
    its ``K`` best-ranked candidates and flies the best of them (``best*2@10-20``). ``~H`` after
    the oracle or ``*K`` stops the rollouts ``H`` minutes after the decision and scores the POSC
    then (``oracle~5@10-20``); ``+VALUE.json`` after it adds a :class:`ValueModel`'s POSC to
    come (``oracle~5+value.json@10-20``)."""
    if not isinstance(spec, str) or not spec:
        raise ConfigError("spec", spec, "a chooser or a chooser model")
    head, at, times = spec.partition("@")
    head, plus, value = head.partition("+")
    head, tilde, h = head.partition("~")
    head, star, k = head.partition("*")
    if star:
        if not k.isdigit():
            raise ConfigError("spec", spec, "NAME*K with K the candidates rolled out (best*2)")
        kwargs = {**kwargs, "lookahead": int(k)}
    if tilde:
        try:
            kwargs = {**kwargs, "horizon_min": float(h)}
        except ValueError:
            raise ConfigError("spec", spec, "NAME~H with H the rollout length in minutes") from None
    if plus:
        if not tilde:
            raise ConfigError("spec", spec, "NAME~H+VALUE.json: a value ends truncated rollouts")
        kwargs = {**kwargs, "value_path": value}
    if head in CHOOSERS and head != "model":
        decide = _minutes("spec", times) if at else (20.0,)
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
    if at:
        decide = _minutes("spec", times)
    return ReplanChoicePolicy("model", str(path), decide_min=decide, **kwargs)
