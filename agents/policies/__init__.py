"""Policies that fly in the environment behind one interface (:class:`base.Policy`), made by
name from one registry (:mod:`poc_env.agents.policies.registry`): ``make_policy("lawnmower")``.

One module per policy family: ``random``, ``lawnmower``, ``greedy`` (``greedy_bayes``),
``game`` (``potential_game``), ``receding`` (``de_receding``), ``de_plan``; ``ppo`` lives with
the RL code (:mod:`poc_env.agents.rl`) and is registered here by name only.
"""

from poc_env.agents.policies.base import Policy
from poc_env.agents.policies.registry import make_policy, register, registered

__all__ = ["Policy", "make_policy", "register", "registered"]
