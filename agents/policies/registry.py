"""Every policy of poc-env by name, in one place: ``make_policy("lawnmower")``.

The registry works as Gymnasium's environment registry does: a name maps to an entry point, a
``"module:attribute"`` string naming a factory (usually the policy class) that is imported only
when a policy of that name is made. So this module imports no policy module, and the policies
layer never imports the RL layer: ``ppo`` points at a class of :mod:`poc_env.agents.rl` by name
only.

A policy registered with an ``argument`` is spelled ``name:VALUE``, and ``VALUE`` is passed to
the factory as that keyword: ``ppo:PATH`` makes ``PPOPolicy(path=PATH)`` (a ``.zip`` or a run
folder; model files are pickle-based, load only trusted files).

Adding a policy touches two files: its module (a :class:`~poc_env.agents.policies.base.Policy`
subclass) and the :func:`register` call at the end of this one. ``poc-env evaluate``,
``poc-env render --policy`` and the Python API all make their policies here::

    from poc_env.agents.policies import make_policy, registered
    registered()                      # ('de_plan', ..., 'random', 'ppo:PATH')
    policy = make_policy("de_plan", popsize=16, maxiter=20)
    policy.reset(env, seed=0)
    actions, _ = policy.predict(observations)
"""

from __future__ import annotations

import importlib
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from poc_env.agents.policies.base import Policy
from poc_env.errors import ConfigError

_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_.-]*$")
_ENTRY_POINT = re.compile(r"^[A-Za-z_][\w.]*:[A-Za-z_]\w*$")


@dataclass(frozen=True)
class PolicySpec:
    """One registered policy: how to make it and how to spell it.

    Parameters
    ----------
    name:
        The registry name (``"lawnmower"``, ``"ppo"``).
    entry_point:
        ``"module:attribute"`` of the factory, imported lazily by :meth:`make`.
    kwargs:
        Keyword arguments every policy of this name gets (a call's own keywords win).
    argument:
        Keyword filled from the ``name:VALUE`` spelling (``"path"`` for ``ppo:PATH``), or None
        for a policy spelled by its name alone.
    argument_help:
        What ``VALUE`` is, for error messages (``"a checkpoint path"``).
    summary:
        One line on what the policy does (``poc-env policies``).
    shipped:
        ``"module:function"`` of a function listing the values (``VALUE``) shipped with the package
        (checkpoints, chooser models: ``ppo:ppo_pilot_paper_6_2``), imported lazily by
        :meth:`shipped_values`; None for a policy that ships none.
    """

    name: str
    entry_point: str
    kwargs: Mapping[str, Any] = field(default_factory=dict)
    argument: str | None = None
    argument_help: str = ""
    summary: str = field(default="", compare=False)  # words, not identity
    shipped: str | None = None

    @property
    def spelling(self) -> str:
        """How users write this policy: ``"lawnmower"`` or ``"ppo:PATH"``."""
        return self.name if self.argument is None else f"{self.name}:{self.argument.upper()}"

    def load(self) -> Callable[..., Policy]:
        """The factory named by :attr:`entry_point` (imported now)."""
        return _attribute(self.entry_point, f"policies[{self.name}].entry_point")

    def shipped_values(self) -> list[str]:
        """The values (``VALUE``) shipped with the package, listed by :attr:`shipped`
        (imported now; none without it)."""
        if self.shipped is None:
            return []
        return list(_attribute(self.shipped, f"policies[{self.name}].shipped")())

    def make(self, value: str | None = None, **kwargs: Any) -> Policy:
        """A fresh policy: the factory called with :attr:`kwargs`, ``kwargs`` and ``value``."""
        args = {**self.kwargs, **kwargs}
        if self.argument is not None:
            args[self.argument] = value
        policy = self.load()(**args)
        if not isinstance(policy, Policy):
            raise ConfigError(
                f"policies[{self.name}].entry_point",
                self.entry_point,
                "a factory returning a poc_env.agents.policies.base.Policy",
            )
        return policy


def _attribute(entry_point: str, where: str) -> Any:
    """The attribute ``entry_point`` (``"module:attr"``) names, imported now; a ConfigError
    naming ``where`` if the module or attribute does not exist."""
    module, _, attr = entry_point.partition(":")
    try:
        return getattr(importlib.import_module(module), attr)
    except (ModuleNotFoundError, AttributeError) as err:
        if isinstance(err, ModuleNotFoundError) and err.name not in _parents(module):
            raise  # a dependency of the module is missing, not the module itself
        raise ConfigError(where, entry_point, "an importable module:attr") from None


def _parents(module: str) -> set[str]:
    parts = module.split(".")
    return {".".join(parts[: i + 1]) for i in range(len(parts))}


_REGISTRY: dict[str, PolicySpec] = {}


def register(
    name: str,
    entry_point: str,
    *,
    kwargs: Mapping[str, Any] | None = None,
    argument: str | None = None,
    argument_help: str = "",
    summary: str = "",
    shipped: str | None = None,
) -> PolicySpec:
    """Register a policy factory under ``name`` (see :class:`PolicySpec` for the parameters).

    Raises
    ------
    ConfigError
        A malformed name or entry point, or a name already registered with another entry.
    """
    if not isinstance(name, str) or not _NAME.match(name):
        raise ConfigError("name", name, "letters, digits, '_', '.', '-' (no ':')")
    if not isinstance(entry_point, str) or not _ENTRY_POINT.match(entry_point):
        raise ConfigError(f"policies[{name}].entry_point", entry_point, "'package.module:attr'")
    if argument is not None and not argument.isidentifier():
        raise ConfigError(f"policies[{name}].argument", argument, "a keyword argument name")
    if shipped is not None and (argument is None or not _ENTRY_POINT.match(str(shipped))):
        raise ConfigError(
            f"policies[{name}].shipped", shipped, "'package.module:function' listing the "
            "shipped values of a policy spelled name:VALUE (an argument), or None",
        )  # fmt: skip
    frozen = MappingProxyType(dict(kwargs or {}))
    spec = PolicySpec(name, entry_point, frozen, argument, argument_help, summary, shipped)
    old = _REGISTRY.get(name)
    if old is not None and old != spec:
        raise ConfigError("name", name, f"a name not registered yet (taken by {old.entry_point})")
    _REGISTRY[name] = spec
    return spec


def registered() -> tuple[str, ...]:
    """Every policy as users spell it: plain names sorted, then ``name:ARG`` ones sorted."""
    plain = sorted(s.spelling for s in _REGISTRY.values() if s.argument is None)
    valued = sorted(s.spelling for s in _REGISTRY.values() if s.argument is not None)
    return (*plain, *valued)


def shipped() -> tuple[str, ...]:
    """Every model shipped with the package as users spell it (``ppo:ppo_pilot_paper_6_2``,
    ``plan_choice:plan_chooser_paper62``): each policy's :meth:`PolicySpec.shipped_values`,
    by policy name, then value (``poc-env policies`` lists them)."""
    return tuple(
        f"{s.name}:{v}" for s in sorted(_REGISTRY.values(), key=lambda s: s.name)
        for v in s.shipped_values()
    )  # fmt: skip


def spec(name: str) -> PolicySpec:
    """The :class:`PolicySpec` of a spelling (``"lawnmower"``, ``"ppo:runs/a"`` or ``"ppo"``)."""
    s = _REGISTRY.get(name.partition(":")[0]) if isinstance(name, str) else None
    if s is None:
        raise ConfigError("policy", name, "one of " + ", ".join(registered()))
    return s


def make_policy(name: str, **kwargs: Any) -> Policy:
    """A fresh policy by its spelling (:func:`registered`); ``kwargs`` go to its factory.

    Raises
    ------
    ConfigError
        An unknown name (the message lists the registered ones), or a ``name:VALUE`` policy
        spelled without its value (or a plain one spelled with one).
    """
    s = spec(name)
    _, sep, value = name.partition(":")
    if s.argument is None:
        if sep:
            raise ConfigError("policy", name, "one of " + ", ".join(registered()))
        return s.make(**kwargs)
    if not value:
        raise ConfigError("policy", name, f"{s.spelling} with {s.argument_help or s.argument}")
    return s.make(value, **kwargs)


#: Read-only view of the registry: name -> :class:`PolicySpec`.
REGISTRY: Mapping[str, PolicySpec] = MappingProxyType(_REGISTRY)

# -- the policies of poc-env -----------------------------------------------------------------
register(
    "random",
    "poc_env.agents.policies.random:RandomPolicy",
    summary="uniform random speed and heading increments (the floor of the increments level)",
)
register(
    "random_heading",
    "poc_env.agents.policies.random:RandomHeadingPolicy",
    summary="a uniform random heading per UAV and step, flown by the heading autopilot",
)
register(
    "random_waypoint",
    "poc_env.agents.policies.random:RandomWaypointPolicy",
    summary="a uniform random target point per UAV and step, flown by the waypoint autopilot",
)
register(
    "lawnmower",
    "poc_env.agents.policies.lawnmower:LawnmowerPolicy",
    summary="parallel strips over the map, split among the UAVs (the classic survey)",
)
register(
    "greedy_bayes",
    "poc_env.agents.policies.greedy:GreedyBayesPolicy",
    summary="each UAV heads for the best reachable cell of the current belief",
)
register(
    "potential_game",
    "poc_env.agents.policies.game:PotentialGamePolicy",
    summary="log-linear learning over heading changes (a potential game on marginal POS)",
)
register(
    "de_receding",
    "poc_env.agents.policies.receding:DERecedingPolicy",
    summary="the paper's §5 loop: adaptive DE picks every UAV's next headings each step",
)
register(
    "de_plan",
    "poc_env.agents.policies.de_plan:DEPlanPolicy",
    summary="the paper's planner: adaptive DE on eq. 26 at take-off, then flies the plan",
)
register(
    "allocation_plan",
    "poc_env.agents.policies.allocation:AllocationPlanPolicy",
    summary="routes from the reach-aware optimal allocation, refined, then flown (best planner)",
)
register(
    "allocation_plan_thorough",
    "poc_env.agents.policies.allocation:AllocationPlanPolicy",
    kwargs={"effort": "thorough"},
    summary="allocation_plan at the thorough effort level: a slower plan of more POS "
    "(docs/PLANNER.md, effort levels)",
)
register(
    "allocation_plan_standard",
    "poc_env.agents.policies.allocation:AllocationPlanPolicy",
    kwargs={"effort": "standard"},
    summary="allocation_plan at the standard effort level: the default plan polished by the "
    "environment's sensor model, within 2 s on paper_6_2 (docs/PLANNER.md, i24-fastpolish, "
    "i24-cheapolish)",
)
register(
    "greedy_rectangles",
    "poc_env.agents.policies.greedy_rectangles:GreedyRectanglesPolicy",
    summary="each UAV the best remaining axis-aligned rectangle it can search, flown as lines",
)
register(
    "optimizer_plan",
    "poc_env.agents.policies.de_plan:DEPlanPolicy",
    argument="optimizer",
    argument_help="an optimiser of the eq. 26 plan (adaptive_de, classic_de, chaotic_abc, "
    "grouped_pso, scipy_de, cmaes)",
    summary="any optimiser's eq. 26 plan, flown as de_plan flies DE's",
)
register(
    "ppo",
    "poc_env.agents.rl.policy:PPOPolicy",
    argument="path",
    argument_help="a checkpoint path (a .zip or a run folder)",
    summary="a stable-baselines3 PPO checkpoint (the rl extra)",
    shipped="poc_env.agents.rl.checkpoint:shipped_checkpoints",
)
register(
    "rllib",
    "poc_env.agents.rl.rllib:RLlibPolicy",
    argument="path",
    argument_help="a run folder of poc-env train --engine rllib",
    summary="an RLlib multi-agent PPO checkpoint (the rllib extra)",
    shipped="poc_env.agents.rl.rllib:shipped_rllib",
)
register(
    "spacetime_plan",
    "poc_env.agents.policies.moving:SpacetimePlanPolicy",
    summary="moving targets: the allocation planner on the co-moving predicted POC, routes "
    "that meet the drifting mass",
)
register(
    "spacetime_receding",
    "poc_env.agents.policies.moving:SpacetimeRecedingPolicy",
    summary="spacetime_plan re-planned every 20 min from the current belief, from where the "
    "UAVs are; a re-plan is flown only if it scores more than the routes being flown",
)
register(
    "receding_choice",
    "poc_env.agents.policies.replan_choice:from_spec",
    argument="spec",
    argument_help="a chooser (rule, best, keep, switch, oracle; @T-T-... for decision times in "
    "minutes) or a chooser model (a .json path or a shipped name)",
    summary="spacetime_receding's re-planning decisions over wider candidates, made by a rule, "
    "a lookahead oracle or a learned chooser",
    shipped="poc_env.agents.policies.replan_choice:shipped_choosers",
)
register(
    "plan_choice",
    "poc_env.agents.policies.plan_choice:from_spec",
    argument="spec",
    argument_help="default, a candidate of the allocation options (sampled, graded, ...) or a "
    "chooser model (a .json path or a shipped name)",
    summary="allocation_plan with the options a learned chooser picks from the prior at "
    "take-off, among variants of about the default's planning cost",
    shipped="poc_env.agents.policies.plan_choice:shipped_choosers",
)
