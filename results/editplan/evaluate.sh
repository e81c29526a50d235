#!/usr/bin/env bash
# i28-editplan: the evaluation, once, on seeds 31000-31049 (no run or selection used them).
# Each policy in its own `poc-env evaluate` run (one thread), timed: CPU seconds per episode
# (user, the flight included: the same flights cost the same, so the difference is planning).
# Then the paired summary against allocation_plan over the union of the runs' episodes.
# Usage: bash results/editplan/evaluate.sh OUT [EXTRA evaluate args, e.g. --overrides ...]
set -euo pipefail
OUT=$1; shift
mkdir -p "$OUT"
for POL in allocation_plan plan_choice:plan_chooser_paper62 plan_choice:graded_sampled; do
  D="$OUT/runs/${POL//:/_}"
  /usr/bin/time -f "$POL user_s %U wall_s %e" -a -o "$OUT/time.txt" \
    env OMP_NUM_THREADS=1 nice -n 10 .venv/bin/poc-env evaluate --scenario paper_6_2 \
    --random-priors --seed 31000 --episodes 50 --policies "$POL" --quiet --out "$D" "$@"
  echo "$(date -u +%H:%M) load $(cut -d' ' -f1-3 /proc/loadavg) after $POL" >> "$OUT/time.txt"
done
# one episodes.csv of every run, then the paired summary (poc-env summarise flies nothing)
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
.venv/bin/poc-env summarise "$OUT" --baseline allocation_plan,plan_choice:graded_sampled
