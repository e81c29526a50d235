"""Reinforcement learning: PPO training with parameter sharing, networks, recipes, checkpoints."""
