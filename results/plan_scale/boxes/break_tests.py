"""i24-boxes: each test of tests/planning/test_polish_boxes.py run with the feature it
checks broken (a one-line change of the source, restored at once): every one must fail.

``python results/plan_scale/boxes/break_tests.py`` (from the repository root; the record is
tests_broken.log). Do not run it beside other processes importing the planner.
"""

import subprocess
import sys

POLISH = "poc_env/agents/planning/polish.py"
OPTIONS = "poc_env/agents/planning/options.py"
ALLOC = "poc_env/agents/planning/allocation.py"
CASES = [
    (
        POLISH,
        "np.clip(c + f * rel + o[None], lo, hi) for o in box_offsets for f in BOX_FITS",
        "pts for o in box_offsets[:0] for f in BOX_FITS",
        "test_a_box_move",
    ),
    (
        POLISH,
        "STRETCH_SCALES = (0.7, 0.85, 1.15, 1.3)",
        "STRETCH_SCALES = (1.0,)",
        "test_a_stretch_move",
    ),
    (
        POLISH,
        "rot = [(np.cos(a), np.sin(a)) for a in np.radians(ROTATIONS)]",
        "rot = [(1.0, 0.0)]",
        "test_a_rotate_move",
    ),
    (
        POLISH,
        "cuts = [sl for j in (1, 2) if len(pts) > j for sl in (slice(j, None), slice(None, -j))]",
        "cuts = []",
        "test_a_trim_move",
    ),
    (POLISH, "got = int(group_move(g))", "got = 0", "test_a_group_move_carries"),
    (
        POLISH,
        "                if count.value > before:",
        "                if False:",
        "test_a_group_move_adds_no",
    ),
    (
        ALLOC,
        "        if not opt.polish_boxes:\n            return out",
        "        if True:\n            return out",
        "test_polish_boxes_option_reaches",
    ),
    (
        OPTIONS,
        '        _number("polish_boxes", self.polish_boxes, 0, 100, integer=True)\n',
        "",
        "test_polish_boxes_option_is_checked",
    ),
    (
        OPTIONS,
        '        _positive_tuple("polish_boxes_radii", self.polish_boxes_radii, high=64.0)\n',
        "",
        "test_polish_boxes_radii_option",
    ),
    (
        POLISH,
        '        raise ConfigError("box_radii", box_radii,',
        '        pass\n        if 0: raise ConfigError("box_radii", box_radii,',
        "test_polish_routes_box_radii",
    ),
]

for path, old, new, test in CASES:
    with open(path) as f:
        src = f.read()
    assert old in src, old
    with open(path, "w") as f:
        f.write(src.replace(old, new, 1))
    try:
        cmd = [sys.executable, "-m", "pytest", "-q", "-x", "tests/planning/test_polish_boxes.py"]
        r = subprocess.run([*cmd, "-k", test], capture_output=True, text=True)
        last = r.stdout.strip().splitlines()[-1]
        print(
            "BROKEN", repr(new[:40]), "->", test, "FAILS" if r.returncode else "still passes", last
        )
    finally:
        with open(path, "w") as f:
            f.write(src)
