"""A learned take-off decision over the allocation planner's options (issue 28, i28-editplan).

The residual on ``allocation_plan`` has no leverage (docs/rl.md, "Planner-guided learning"): the
waypoint follower pulls a UAV back onto its route every step. This policy edits the plan where it
is made instead: at take-off it picks one of :data:`CANDIDATES`, variants of the default
allocation options (:class:`~poc_env.agents.planning.options.PlanOptions`) that cost about what
the default costs to plan (graded lines, sampled scores, other line spacings, turned boxes, ...),
from the prior alone, and plans and flies that one. The decision reads the prior's
:func:`prior_features` (milliseconds) and plans one candidate, so its planning cost is the
chosen candidate's: no candidate is planned or flown to decide (that would be a lookahead, or
the planner at K times its effort).

``plan_choice:SPEC`` (:func:`from_spec`), ``SPEC`` one of

``default``
    ``allocation_plan`` itself: flies exactly its episode (``tests/policies/test_plan_choice.py``).
``NAME`` (a candidate's name, e.g. ``sampled``)
    always candidate ``NAME`` (a constant variant: the baselines of a chooser).
a chooser model
    a :class:`PlanChoiceModel` (a JSON file, or the name of one shipped in
    ``agents/checkpoints/plan_choosers/``, e.g. ``plan_chooser_paper62``): predicts each
    candidate's flown gain over ``default`` from the prior's features and plans the candidate
    of the highest prediction (``default`` if none is predicted above 0).

Every reset records the decision in ``self.decision`` (the candidate chosen, and for a model
the features and predictions; CPU seconds of the choice and of the plan).

Measured (docs/rl.md, "Learned plan choice at take-off (i28-editplan)"): on 50 evaluation
priors of ``paper_6_2`` the shipped chooser flies +0.0158 +- 0.0030 above ``allocation_plan``,
and the constant ``plan_choice:sampled`` +0.0156 +- 0.0032: the gain is that option's, the
learned choice adds +0.0002 +- 0.0006 to it.
"""

from __future__ import annotations

import math
import time
from typing import Any, ClassVar

import numpy as np

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.options import PlanOptions
from poc_env.agents.policies.base import PlanPolicy
from poc_env.agents.policies.replan_choice import ChooserModel
from poc_env.errors import ConfigError

#: the candidates: name -> changes to the default :class:`PlanOptions` (``default``: none).
#: Each plans in about the default's time on ``paper_6_2`` (1.0-1.4 times its CPU time, median
#: over the training priors; results/editplan/README.md); the slower ideas (boxes at 45 degrees,
#: relaxation patches, excursions, the polish) are left out.
CANDIDATES: dict[str, dict[str, Any]] = {
    "default": {},
    "graded": {"graded": True},
    "sampled": {"sampled": True},
    "graded_sampled": {"graded": True, "sampled": True, "refine_sampled": True},
    "spacings_b": {"spacings": (1.25, 1.75, 2.5, 3.5, 5.0)},
    "dense05": {"dense_spacings": (0.5, 0.75)},
    "axis": {"axis": True},
    "levels_wide": {"levels": (2, 3, 4, 5, 6, 8)},
    "chain_early": {"chain_early": True},
}

#: names of :func:`prior_features`' columns.
PRIOR_FEATURES = (
    "mass",  # the prior's mass in the map
    "spread",  # standard distance of the mass from its centroid / map diagonal
    "aniso",  # 1 - minor / major eigenvalue of the mass's covariance
    "axis_cos",  # cos 2 theta of the mass's principal axis (theta from the map's x axis)
    "axis_sin",  # sin 2 theta
    "reach_mean",  # mean distance of the mass to its nearest airfield / the UAV's reach
    "reach_sd",  # its standard deviation / the reach
    "far",  # share of the mass farther than half the reach from every airfield
    "entropy",  # normalised entropy of the prior over the cells
    "top",  # share of the mass in the top tenth of the cells
    "peaks",  # local maxima above twice the mean cell / 10
    "field_share",  # largest share of the mass nearest one airfield
    "floor",  # least cell over the mean cell (the uniform background)
)


def prior_features(scenario: Any, prior: np.ndarray) -> np.ndarray:
    """``(len(PRIOR_FEATURES),)`` features of a prior (``(ny, nx)`` cell masses) on
    ``scenario``'s map and airfields (module docstring: the chooser's only inputs).

    The reach is the distance a UAV flies out on half its usable endurance (eq. 18) at cruise
    speed."""
    from poc_env.theory.probability_map import Grid

    p = np.asarray(prior, dtype=float)
    grid = Grid.from_config(scenario.map)
    if p.shape != (grid.ny, grid.nx):
        raise ConfigError("prior", p.shape, f"cell masses of shape {(grid.ny, grid.nx)}")
    xy = grid.centers.reshape(-1, 2)
    w = p.reshape(-1)
    mass = float(w.sum())
    if not mass > 0:
        return np.zeros(len(PRIOR_FEATURES))
    q = w / mass
    diag = math.hypot(grid.width_m, grid.height_m)
    mu = q @ xy
    d = xy - mu
    cov = (d * q[:, None]).T @ d
    ev, vec = np.linalg.eigh(cov)
    theta = math.atan2(vec[1, 1], vec[0, 1])
    fields = np.array([a.position_m for a in scenario.airfields], dtype=float)
    near = np.hypot(*(xy[:, None, :] - fields[None, :, :]).transpose(2, 0, 1))  # (cells, fields)
    dist = near.min(axis=1)
    u = scenario.uav
    reach = 0.5 * u.usable_endurance_s * u.cruise_speed_mps
    rm = float(q @ dist)
    share = np.bincount(near.argmin(axis=1), weights=q, minlength=len(fields))
    nz = q[q > 0]
    top = np.sort(q)[::-1][: max(1, len(q) // 10)].sum()
    mean_cell = 1.0 / len(q)
    pad = np.pad(p / mass, 1, constant_values=-1.0)
    centre = pad[1:-1, 1:-1]
    is_max = np.ones_like(centre, dtype=bool)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            if dy or dx:
                nb = pad[1 + dy : pad.shape[0] - 1 + dy, 1 + dx : pad.shape[1] - 1 + dx]
                is_max &= centre >= nb
    peaks = int(np.sum(is_max & (centre > 2.0 * mean_cell)))
    return np.array(
        [
            mass,
            math.sqrt(max(float(np.trace(cov)), 0.0)) / diag,
            1.0 - float(ev[0]) / max(float(ev[1]), 1e-12),
            math.cos(2 * theta),
            math.sin(2 * theta),
            rm / reach,
            math.sqrt(max(float(q @ (dist - rm) ** 2), 0.0)) / reach,
            float(q[dist > 0.5 * reach].sum()),
            float(-(nz * np.log(nz)).sum() / math.log(len(q))),
            float(top),
            peaks / 10.0,
            float(share.max()),
            float(q.min() / mean_cell),
        ]
    )


#: the candidates a model predicts a gain for (all but ``default``), in its one-hot's order.
KINDS = tuple(k for k in CANDIDATES if k != "default")
#: a model's input columns: the prior's features and the candidate's one-hot.
FEATURES = (*PRIOR_FEATURES, *(f"kind_{k}" for k in KINDS))
#: the expansions a :class:`PlanChoiceModel` may use (:func:`expand`).
EXPANSIONS = ("kinds", "interact")


def rows(x_prior: np.ndarray, kinds: tuple[str, ...] = KINDS) -> np.ndarray:
    """``(len(kinds), len(FEATURES))``: one row per candidate of ``kinds``, the prior's
    features then the candidate's one-hot."""
    x = np.asarray(x_prior, dtype=float).reshape(-1)
    if x.shape != (len(PRIOR_FEATURES),):
        raise ConfigError("features", x.shape, f"{len(PRIOR_FEATURES)} prior features")
    out = np.zeros((len(kinds), len(FEATURES)))
    out[:, : len(PRIOR_FEATURES)] = x
    for i, k in enumerate(kinds):
        out[i, len(PRIOR_FEATURES) + KINDS.index(k)] = 1.0
    return out


def expand(x: np.ndarray, how: str) -> np.ndarray:
    """A model's inputs from :func:`rows`: ``"kinds"`` the one-hot alone (a constant gain per
    candidate: what each variant gains on average); ``"interact"`` adds every prior feature
    times every candidate's one-hot (a linear model of the prior per candidate)."""
    if how not in EXPANSIONS:
        raise ConfigError("expand", how, f"one of {', '.join(EXPANSIONS)}")
    x = np.asarray(x, dtype=float).reshape(-1, len(FEATURES))
    n = len(PRIOR_FEATURES)
    kinds = x[:, n:]
    cols = [kinds]
    if how == "interact":
        cols.append((x[:, :n, None] * kinds[:, None, :]).reshape(len(x), -1))
    return np.hstack(cols)


class PlanChoiceModel(ChooserModel):
    """:class:`~poc_env.agents.policies.replan_choice.ChooserModel`'s ridge regression (and
    JSON format) over this module's :data:`FEATURES` and :func:`expand`: a candidate's flown
    POSC gain over ``default`` from the prior."""

    COLUMNS: ClassVar[tuple[str, ...]] = FEATURES

    @staticmethod
    def expand(x: np.ndarray, how: str) -> np.ndarray:
        return expand(x, how)


def options_of(name: str) -> PlanOptions:
    """The :class:`PlanOptions` of candidate ``name`` (:data:`CANDIDATES`)."""
    if name not in CANDIDATES:
        raise ConfigError("candidate", name, f"one of {', '.join(CANDIDATES)}")
    return PlanOptions(**CANDIDATES[name])


def _folder() -> Any:
    import importlib.resources

    return importlib.resources.files("poc_env.agents").joinpath("checkpoints", "plan_choosers")


def shipped_choosers() -> list[str]:
    """The names of the chooser models shipped in ``agents/checkpoints/plan_choosers/``: the
    names of ``plan_choice:NAME``, a folder per policy as ``receding_choice:NAME``'s
    ``choosers/`` (both are :class:`ChooserModel` JSON; a model of the other policy is refused
    by its features, and a shared folder would offer each policy the other's names)."""
    folder = _folder()
    if not folder.is_dir():
        return []
    return sorted(f.name[:-5] for f in folder.iterdir() if f.name.endswith(".json"))


CHOOSERS = ("default", "fixed", "model")


class PlanChoicePolicy(PlanPolicy):
    """``plan_choice:SPEC``: the allocation plan of the candidate a chooser picks from the
    prior (module docstring).

    Parameters
    ----------
    chooser:
        ``"default"``, ``"fixed"`` (with ``fixed``) or ``"model"`` (with ``model``).
    fixed:
        The candidate of ``"fixed"``.
    model:
        The :class:`PlanChoiceModel` of ``"model"``.
    """

    name = "plan_choice"

    def __init__(
        self,
        chooser: str = "default",
        fixed: str | None = None,
        model: PlanChoiceModel | None = None,
    ) -> None:
        if chooser not in CHOOSERS:
            raise ConfigError("chooser", chooser, f"one of {', '.join(CHOOSERS)}")
        if chooser == "fixed":
            options_of(str(fixed))  # refuses an unknown candidate
        if chooser == "model" and not isinstance(model, PlanChoiceModel):
            raise ConfigError("model", model, "a PlanChoiceModel")
        self.chooser = chooser
        self.fixed = fixed
        self.model = model
        self.decision: dict[str, Any] = {}

    def choose(self, env: Any, prior: np.ndarray, seed: int) -> tuple[str, dict]:
        """The candidate to plan and what the choice read (features, predictions)."""
        if self.chooser == "default":
            return "default", {}
        if self.chooser == "fixed":
            return str(self.fixed), {}
        assert self.model is not None
        x = prior_features(env.scenario, prior)
        pred = self.model.predict(rows(x))
        j = int(np.argmax(pred))
        name = KINDS[j] if pred[j] > 0 else "default"
        return name, {"features": x.tolist(), "predicted": dict(zip(KINDS, pred.tolist()))}

    def make(self, env: Any, prior: np.ndarray, seed: int) -> dict:
        t0 = time.process_time()
        name, read = self.choose(env, prior, seed)
        t1 = time.process_time()
        plan = make_allocation_plan(env.scenario, prior=prior, seed=seed, options=options_of(name))
        t2 = time.process_time()
        self.decision = {"chosen": name, **read, "choose_s": t1 - t0, "plan_s": t2 - t1}
        return plan


def from_spec(spec: str, **kwargs: Any) -> PlanChoicePolicy:
    """The policy of ``plan_choice:SPEC``: ``default``, a candidate's name (always that
    candidate, :data:`CANDIDATES`), or a chooser model: a ``.json`` path or the name of a
    shipped one (:func:`shipped_choosers`)."""
    if not isinstance(spec, str) or not spec:
        raise ConfigError("spec", spec, "a candidate or a chooser model")
    if spec == "default":
        return PlanChoicePolicy("default", **kwargs)
    if spec in CANDIDATES:
        return PlanChoicePolicy("fixed", fixed=spec, **kwargs)
    path: str = spec
    if spec in shipped_choosers():
        path = str(_folder().joinpath(f"{spec}.json"))
    elif not spec.endswith(".json"):
        raise ConfigError(
            "spec",
            spec,
            f"a candidate ({', '.join(CANDIDATES)}), a chooser model .json or a shipped one "
            f"({', '.join(shipped_choosers()) or 'none'})",
        )
    return PlanChoicePolicy("model", model=PlanChoiceModel.load(path), **kwargs)
