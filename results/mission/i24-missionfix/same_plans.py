"""``python same_plans.py A.json B.json``: whether two plan.json files are equal but for
``runtime_s`` (the departure changes only missions main refused)."""

import json
import sys
from pathlib import Path

a, b = (json.loads(Path(p).read_text()) for p in sys.argv[1:3])
for d in (a, b):
    d.pop("runtime_s", None)
print(sys.argv[1], sys.argv[2], "same (without runtime_s)" if a == b else "DIFF")
