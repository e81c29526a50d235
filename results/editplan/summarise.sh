#!/usr/bin/env bash
# One episodes.csv of every run of results/editplan/evaluate.sh OUT ..., then the paired
# summary against allocation_plan and the constant plan_choice:sampled (flies nothing).
set -euo pipefail
OUT=$1
python3 - "$OUT" <<'PY'
import csv, glob, sys
out = sys.argv[1]
rows, head = [], None
for p in sorted(glob.glob(f"{out}/runs/*/episodes.csv")):
    with open(p) as f:
        r = list(csv.reader(f))
    head = r[0]
    rows += r[1:]
with open(f"{out}/episodes.csv", "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(head)
    w.writerows(rows)
PY
.venv/bin/poc-env summarise "$OUT" --baseline allocation_plan,plan_choice:sampled
