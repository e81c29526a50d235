"""i24-speed: each fast path broken once (a one-line change), its test in
tests/planning/test_speed.py run, the file restored. Run from the repository root:
``python results/plan_scale/speed/break_tests.py`` (every line must end ``1 failed``)."""

import os
import subprocess

K = "agents/planning/_kernels.py"
R = "agents/planning/refine.py"
C = "agents/planning/coverage_boxes.py"
ROUTE = "(pod_from_coverage(self.cov[m] + 1.0 / s, law) - self.base[m])"
# (file, the line as it is, the line broken, the test that must fail)
BREAKS = [
    ("agents/planning/allocation.py",
     "d = np.hypot(to[..., 0], to[..., 1]) + np.hypot(la[..., 0], la[..., 1])",
     "d = np.hypot(to[..., 0], to[..., 1])", "test_nearest_field_is_the_line_by_line_field"),
    (R, "    ends[o + 1 :: 2] = b\n", "    ends[o + 1 :: 2] = a\n",
     "test_candidate_edits_are_the_loops"),
    (R, "        mark[cells] = False\n", "", "test_move_gains_with_scratch_equal_without"),
    (R, "        self._current.clear()  # every UAV's pairs with k changed\n", "",
     "test_airspace_count_keeps_a_uavs_pairs_only_until_a_move_is_kept"),
    (K, "                if m < need:\n", "                if m <= need:\n",
     "test_airspace_count_keeps_a_uavs_pairs_only_until_a_move_is_kept"),
    (K, "        buf[nh + kept + 1, 0] = ax + 0.0 * dx\n",
     "        buf[nh + kept + 1, 0] = ax + 0.5 * dx\n", "test_cut_route_is_cut_lines"),
    (K, "                    e = c1 + nw\n", "                    e = c1 + nw - 1\n",
     "test_box_search_bounds_skip_only_losing_boxes"),
    (C, "return (b[:, 0, :, 0] + b[:, 0, :, 1]) + (b[:, 1, :, 0] + b[:, 1, :, 1])",
     "return (b[:, 0, :, 0] + b[:, 1, :, 0]) + (b[:, 0, :, 1] + b[:, 1, :, 1])",
     "test_block_sums_are_numpys"),
    (C, "    return float(np.sum(g))\n", "    return float(np.sum(g[m]))\n",
     "test_added_gain_is_the_full_sum"),
    (C, ROUTE, ROUTE.replace("self.base[m]", "self.parent.base[m]"),
     "test_derived_gain_tables_give_the_recomputed_routes"),
]  # fmt: skip

for path, old, new, test in BREAKS:
    with open(path) as f:
        src = f.read()
    assert src.count(old) == 1, (path, old)
    with open(path, "w") as f:
        f.write(src.replace(old, new))
    try:
        r = subprocess.run(
            [".venv/bin/pytest", "-q", "-x", f"tests/planning/test_speed.py::{test}"],
            capture_output=True,
            text=True,
            env={**os.environ, "OMP_NUM_THREADS": "1"},
        )
        print(f"{test} ({path}): broken -> {r.stdout.strip().splitlines()[-1]}", flush=True)
    finally:
        with open(path, "w") as f:
            f.write(src)
