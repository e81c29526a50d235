"""i24-bigpolish: each new test fails with its feature broken (a script, not a test).

``python break_tests.py`` (from the checkout): per break, the source line replaced, the test
run, the file restored; one line per break (``FAILS (good)`` and pytest's first ``E`` lines).
"""

import os
import subprocess
from pathlib import Path

BREAKS = [
    ("engage: big maps skipped again", "agents/planning/allocation.py",
     "elif polishing and big and not opt.polish_big_work:", "elif polishing and big:",
     "test_the_big_map_polish_engages_above_the_cell_limit_and_keeps_the_rules"),
    ("budget never stops", "agents/planning/polish.py",
     "if work is not None and ex.scored >= work:", "if False:",
     "test_the_budget_stops_the_search_where_the_unbounded_one_was"),
    ("steps not counted", "agents/planning/polish.py",
     "self.scored += len(na)", "self.scored += 0",
     "test_the_budget_stops_the_search_where_the_unbounded_one_was"),
    ("big lines passes ignored", "agents/planning/allocation.py",
     "lines = opt.polish_big_lines or opt.polish_lines if big else opt.polish_lines",
     "lines = opt.polish_lines",
     "test_big_lines_passes_reach_the_second_polish_on_big_maps_only"),
    ("option not checked", "agents/planning/options.py",
     '_number("polish_big_work", self.polish_big_work, 0, 1e12, integer=True)', "pass",
     "test_big_polish_options_are_checked"),
    ("work arg not checked", "agents/planning/polish.py",
     'raise ConfigError("work", work, "None or an integer >= 0 (candidate steps)")', "pass",
     "test_the_work_argument_is_checked"),
    ("note missing", "agents/planning/planner.py",
     'if polish.get("spent"):', "if False:",
     "test_the_plan_summary_says_when_the_budget_stopped_the_polish"),
]  # fmt: skip

for name, path, old, new, test in BREAKS:
    p = Path(path)
    src = p.read_text()
    assert src.count(old) == 1, name
    p.write_text(src.replace(old, new))
    try:
        r = subprocess.run(
            [".venv/bin/pytest", "-q", "tests/planning/test_bigpolish.py", "-k", test],
            capture_output=True, text=True, env={**os.environ, "OMP_NUM_THREADS": "1"},
        )  # fmt: skip
        lines = r.stdout.strip().splitlines()
        why = " ; ".join([ln[:150] for ln in lines if ln.startswith("E ")][:2])
        verdict = "FAILS (good)" if r.returncode else "PASSES (bad)"
        print(f"{name}: {test}: {verdict}: {lines[-1]} | {why}", flush=True)
    finally:
        p.write_text(src)
