#!/bin/sh
# i24-relax: every pairing quoted in README.md, into paired_validation.txt (from the repo root).
D=results/plan_scale/relax
P=".venv/bin/python $D/paired.py"
TL="results/plan_scale/boxes/val_stage2_routes_large_400.json,results/plan_scale/boxes/val_thorough_large_400_b.json"
TV="all+block/0.125:0.25:0.5:1:2/6|thorough"
TP=results/plan_scale/lines/val_stage2_routes_paper_6_2.json
{
for m in large_400 paper_6_2; do
  echo "== $m: the first version (val_$m.json) over the default plan"
  for v in start "default+relax_start=1" "default+box_start=0+relax_start=1"; do
    $P $D/val_$m.json "$v" $D/val_$m.json default; echo; done
  echo "== $m: this branch's version (val2_$m.json) over the default plan"
  for v in start "default+relax_start=1" "default+box_start=0+relax_start=1"; do
    $P $D/val2_$m.json "$v" $D/val_$m.json default; echo; done
  echo "== $m: this branch's start over the first version's"
  $P $D/val2_$m.json start $D/val_$m.json start; echo
done
echo "== large_400: thorough with the start over the stored thorough plans"
$P $D/val_thorough_large_400.json "thorough+relax_start=1" "$TL" "$TV"; echo
echo "== paper_6_2: thorough with the start over the stored thorough plans"
$P $D/val_thorough_paper_6_2.json "thorough+relax_start=1" $TP "$TV"; echo
} > $D/paired_validation.txt 2>&1
