"""Policies that fly in the environment behind one interface (:class:`base.Policy`), made by
name from one registry (:mod:`agents.policies.registry`): ``make_policy("lawnmower")``.

One module per policy family: ``random``, ``lawnmower``, ``greedy`` (``greedy_bayes``),
``game`` (``potential_game``), ``receding`` (``de_receding``), ``de_plan``; ``ppo`` lives with
the RL code (:mod:`agents.rl`) and is registered here by name only.
"""

from agents.policies.base import Policy
from agents.policies.registry import make_policy, register, registered

__all__ = ["Policy", "make_policy", "register", "registered"]
