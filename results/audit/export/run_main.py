"""Run a script with ``poc_env`` imported from main's tree (``git archive main`` unpacked in
/tmp/export-audit/mainsrc, or the folder ``POC_ENV_TREE`` names) instead of this checkout's
editable install: ``python run_main.py SCRIPT ARGS...`` (export-audit's before/after glide
measurement; leftovers' before/after probes)."""

import os
import runpy
import sys

editable = [
    f for f in sys.meta_path if "editable" in getattr(f, "__name__", type(f).__name__).lower()
]
sys.meta_path[:] = [f for f in sys.meta_path if f not in editable]
sys.path.insert(0, os.environ.get("POC_ENV_TREE", "/tmp/export-audit/mainsrc"))
sys.argv = sys.argv[1:]
runpy.run_path(sys.argv[0], run_name="__main__")
