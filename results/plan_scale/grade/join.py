"""Join the two processes' flight records (a: seeds 0-24, b: 25-49) into one file, by seed."""

import json
import sys

out, *parts = sys.argv[1:]
recs = []
for p in parts:
    with open(p) as f:
        recs += json.load(f)
recs.sort(key=lambda r: (r["seed"], r["variant"]))
with open(out, "w") as f:
    json.dump(recs, f, indent=1)
print(out, len(recs))
