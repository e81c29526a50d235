"""Thin adapters over :mod:`poc_env.sim`: the PettingZoo parallel environment (``parallel``),
its Gymnasium single-agent view (``gymnasium_env``) and the batched SB3 VecEnv (``vector``)."""
