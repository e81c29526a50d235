"""Policies and planners that fly in poc-env: the paper's DE planner, baselines, RL."""
