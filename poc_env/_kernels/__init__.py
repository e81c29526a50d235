"""Every compiled (numba) function of poc_env, one private module per thing it computes.

==================  ==========================================================================
module              kernels (the public functions that call them)
==================  ==========================================================================
``sensing``         the detection laws' compiled branches (``LAW_CODES``), their array forms
                    and the fused sensing sweep of eq. 12-14 (:mod:`poc_env.theory.search_theory`),
                    the hidden target's POD and the eq. 19 kinematics (:mod:`poc_env.sim.core`),
                    the three in one call (:mod:`poc_env.sim.single`)
``swarm``           pairwise distances, the eq. 20-21 checks (:mod:`poc_env.sim.constraints`),
                    the eq. 24 graphs and the auto topology (:mod:`poc_env.sim.comms`), the
                    simulator step's bookkeeping that applies them
                    (:mod:`poc_env.sim.core`); the single env's end of step: reward terms and
                    total, episode end, info values, sums in numpy's pairwise order, and the
                    bookkeeping, topology and end of step in one call (:mod:`poc_env.sim.single`)
``autopilot``       the heading and waypoint levels' autopilot and eq. 18 return rule
                    (:func:`poc_env.sim.control.swarm_increments`)
``observations``    rasters, vectors and compass sums (:mod:`poc_env.sim.observations`)
``adapters``        the batched adapters' bookkeeping of a step: the SB3 slots' rewards, dones
                    and returns (:class:`poc_env.envs.vector.SwarmVecEnv`), the mean over live
                    agents (:func:`poc_env.sim.engine.mean_over`)
``priors``          a Gaussian-mixture prior's exponent and sub-cell sums
                    (:func:`poc_env.theory.probability_map.gaussian_mixture`)
``rectangles``      area fractions and weighted masses of rotated rectangles over grid cells
                    (:mod:`poc_env.theory.regions`, the planner's objective)
``segments``        segments against polygon edges with certified orientation signs (the
                    zone router's visibility and clipping tests, :mod:`poc_env.sim.routing`)
==================  ==========================================================================

The planner's own kernels (its rectangle pass, route timing) are
:mod:`poc_env.agents.planning._kernels`, under the same rule.

**The cache rule: a kernel module imports nothing of the project.** Numba's on-disk cache
(``cache=True``) checks only the source file of the function it compiles. A compiled function
that calls a compiled function of another file, or reads a constant of another file (numba
freezes globals into the machine code), would keep running a stale copy of it after that file
is edited; so would one whose decorator options came from another file. A kernel module
therefore imports only the standard library, numpy, numba and llvmlite: every function a kernel
calls, every constant it reads and the options it is compiled with are in its own file, and an
edit of that file invalidates exactly the kernels that could see it. A group that needs another
group's arithmetic owns it (the step owns the distances and eq. 20-24 checks that
``constraints`` and ``comms`` also call; the vector observation counts its neighbours with its
own loop, pinned to ``comms.in_range`` by the tests; the hidden target's POD sits with the
laws, and so do the kinematics, which the single env's step flies and senses in one call), or
the Python caller composes kernels of two modules (the planner's rectangle pass, then
:func:`~poc_env._kernels.rectangles.rectangle_masses`).

``tests/sim/test_kernels.py`` enforces the rule:
``test_kernel_modules_import_nothing_of_the_project`` reads each kernel module's imports,
``test_compiled_functions_call_only_their_own_module`` follows the loaded dispatchers'
globals, ``test_cache_rule_catches_a_call_into_another_kernel_module`` shows both checkers
catch a violation, and ``test_compiled_code_lives_only_in_kernel_modules`` keeps numba out of
every other module.

Each module compiles with ``error_model="numpy"`` (``x / 0`` is an inf, not an exception);
``inline="always"`` lets the compiler vectorise inner loops. This package's ``__init__``
imports nothing, so importing one group does not load the others.
"""
