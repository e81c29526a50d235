"""Reinforcement learning with stable-baselines3 PPO (the ``rl`` extra) and RLlib (``rllib``).

``args``        :class:`~poc_env.agents.rl.args.TrainArgs`, the options of ``poc-env train``
``train``       env and model factories, :func:`~poc_env.agents.rl.train.train` (the entry point)
``checkpoint``  atomic checkpoints, resume, generator states, loading model files
``networks``    the CNN+MLP feature extractor of the ``shared`` recipe
``pilot``       the ``pilot`` recipe: PPO picks headings, an autopilot flies eq. 19
``policy``      :class:`~poc_env.agents.rl.policy.PPOPolicy`, a checkpoint behind the Policy
                interface
``curve``       the training curve of a run (``poc-env curve``)
``card``        a shipped checkpoint's card (where it came from, how it scored)
``frameworks``  the registered tasks as environments of third-party RL frameworks
``bc``          the behaviour-cloning warm start (``--bc-teacher``)
``rllib``       RLlib multi-agent PPO (``--engine rllib``) and its policies
``cluster``     Ray sessions (a local instance or a probed cluster address) for RLlib training
                and ``poc-env evaluate/experiment --ray``
"""
