"""i24-budget: where `standard`'s CPU goes on ``paper_6_2``, function by function (a script).

``python results/plan_scale/budget/profile_fn.py SEEDS OUT.prof [VARIANT]`` (SEEDS
comma-separated, -1 the map's own prior): after a warm-up plan, ``VARIANT``'s (default
``standard``) plan of each prior under cProfile (one profile over all priors, written to
``OUT.prof``); prints the top functions by exclusive and inclusive time. Compiled kernels
show as one call each (their inside is not seen).
"""

import cProfile
import pstats
import sys
import time

sys.path.insert(0, "tests/planning")

from effort_ab import _options

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.config import load_scenario
from poc_env.theory.probability_map import build_prior


def main(seeds, out, variant="standard"):
    sc = load_scenario("paper_6_2")
    opt = _options(variant)
    make_allocation_plan(sc, options=opt)  # warm-up (JIT)
    priors = [build_prior(sc.map) if s < 0 else episode_prior(sc, s) for s in seeds]
    pr = cProfile.Profile(time.process_time)
    c0 = time.process_time()
    pr.enable()
    for prior in priors:
        make_allocation_plan(sc, prior=prior, options=opt)
    pr.disable()
    print(f"cpu {time.process_time() - c0:.2f} s over {len(seeds)} plans", flush=True)
    pr.dump_stats(out)
    st = pstats.Stats(out)
    st.sort_stats("tottime").print_stats(35)
    st.sort_stats("cumulative").print_stats(40)


if __name__ == "__main__":
    main([int(s) for s in sys.argv[1].split(",")], sys.argv[2], *sys.argv[3:])
