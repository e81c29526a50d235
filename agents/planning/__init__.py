"""The paper's planner and its relatives: the DE objective (eq. 25-26), optimizers (adaptive DE
eq. 27-32, CMA-ES, PSO), the rectangle planner, region planning and surveys (§6.1).
Plans are written and exported by :mod:`poc_env.agents.mission`."""
