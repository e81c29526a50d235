"""Join the two flight runs' records (priors 0-24 and 25-49) into flown_paper_6_2.json."""

import json
import os

here = os.path.dirname(os.path.abspath(__file__))
recs = []
for part in ("a", "b"):
    with open(os.path.join(here, f"flown_paper_6_2_{part}.json")) as f:
        recs += json.load(f)
out = os.path.join(here, "flown_paper_6_2.json")
with open(out + ".tmp", "w") as f:
    json.dump(recs, f, indent=1)
os.replace(out + ".tmp", out)
print(len(recs), "records")
