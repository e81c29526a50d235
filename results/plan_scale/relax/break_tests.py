"""i24-relax: each test of tests/planning/test_relax_patches.py run with the feature it checks
broken (a one-line change of the source, restored at once): every one must fail.

``python results/plan_scale/relax/break_tests.py [ROOT]``: ROOT (default: the repository
root) is the checkout whose sources are changed and tested, run with ``PYTHONPATH=ROOT`` so a
copy (``rsync -a --exclude .venv --exclude results REPO/ COPY/``) can be broken while other
processes import the repository's planner. The record is tests_broken.log.
"""

import os
import subprocess
import sys

RELAX = "agents/planning/relax_patches.py"
OPTIONS = "agents/planning/options.py"
ALLOC = "agents/planning/allocation.py"
CASES = [
    (RELAX, "wps = cut_lines(wps, fits, w, options)[0]", "wps = wps", "test_routes_keep_eq_17_18"),
    (RELAX, "part = sectors(tau[g[0]].ravel()[cells], load, bearing, len(g))",
     "part = sectors(tau[g[0]].ravel()[cells], load, bearing, 1)", "test_routes_keep_eq_17_18"),
    (RELAX, "part = sectors(tau[g[0]].ravel()[cells], load, bearing, len(g))",
     "part = sectors(tau[g[0]].ravel()[cells], load, bearing, 1)", "test_a_uav_that_reaches_no"),
    (RELAX, "    z_use = cell_area_m2 / (rate * (budget - tf[fi, cells[ji]]))",
     "    z_use = 0.5 * cell_area_m2 / (rate * (budget - tf[fi, cells[ji]]))",
     "test_dedicated_allocation_keeps"),
    (RELAX, "    part[order] = cut(hi)", "    part = cut(hi)", "test_sectors_cut_by_bearing"),
    (ALLOC, "    if best is not None and opt.relax_start:", "    if False:",
     "test_option_puts_the_start"),
    (ALLOC, "            r_routes = _lawnmower_start(r_routes)",
     "            r_routes = fit_lawnmowers(r_routes, takeoff, landing, sc, v, heading0, opt)",
     "test_the_start_goes_around"),
    (OPTIONS, '        _positive_tuple("relax_scales", self.relax_scales, high=1.0)\n', "",
     "test_bad_relax_options"),
    (OPTIONS, '"relax_start", "chain_early"', '"chain_early"', "test_bad_relax_options"),
    (OPTIONS, '        _positive_tuple("relax_etas", self.relax_etas, high=1.0)\n', "",
     "test_bad_relax_options"),
]  # fmt: skip


def main(root: str) -> None:
    env = {**os.environ, "PYTHONPATH": root}
    py = os.path.join(os.path.dirname(sys.executable), "pytest")
    for path, old, new, test in CASES:
        full = os.path.join(root, path)
        with open(full) as f:
            src = f.read()
        assert src.count(old) == 1, (path, old)
        try:
            with open(full, "w") as f:
                f.write(src.replace(old, new))
            res = subprocess.run(
                [py, "-q", "-x", "-p", "no:cacheprovider",
                 os.path.join(root, "tests/planning/test_relax_patches.py"), "-k", test],
                capture_output=True, text=True, env=env, cwd=root,
            )  # fmt: skip
        finally:
            with open(full, "w") as f:
                f.write(src)
        last = res.stdout.strip().splitlines()[-1] if res.stdout.strip() else res.stderr[-200:]
        status = "FAILS (good)" if res.returncode != 0 else "PASSES (bad)"
        print(f"{status}: {test} with {path}: {old.strip()[:60]!r} -> {new.strip()[:40]!r}: {last}",
              flush=True)  # fmt: skip


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else os.getcwd())
