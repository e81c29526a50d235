"""i24-sampled: eq. 21 / 24 violation steps per flight of ``fly`` records, paired per prior
(Student's t 95 %): ``python viol_pair.py RECORDS.json BASE OTHER``."""

import json
import sys

import numpy as np

from poc_env.stats import ci95

with open(sys.argv[1]) as f:
    recs = json.load(f)
by = {(r["seed"], r["variant"]): r for r in recs}
base, other = sys.argv[2], sys.argv[3]
seeds = sorted(s for s, v in by if v == other and (s, base) in by)
d = np.array([by[s, other]["violations"] - by[s, base]["violations"] for s in seeds], float)
g = np.array([(by[s, other]["posc"] - by[s, base]["posc"]) / by[s, base]["rule_bound"]
              for s in seeds])  # fmt: skip
print(
    f"{other} - {base} (n {len(seeds)}): flown/rule {g.mean():+.4f} +- {ci95(g):.4f} "
    f"{(g > 1e-9).sum()}/{(abs(g) <= 1e-9).sum()}/{(g < -1e-9).sum()}; violation steps "
    f"{d.mean():+.2f} +- {ci95(d):.2f} (more on {(d > 0).sum()}, equal {(d == 0).sum()}, "
    f"fewer {(d < 0).sum()}); mean {np.mean([by[s, base]['violations'] for s in seeds]):.2f} "
    f"-> {np.mean([by[s, other]['violations'] for s in seeds]):.2f}"
)
