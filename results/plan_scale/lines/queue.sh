#!/bin/sh
# i24-lines: background queue (niced), one process at a time
cd /work/wt/i24-lines
export PYTHONPATH=/work/wt/i24-lines OMP_NUM_THREADS=1
PY=/work/main/.venv/bin/python
O=results/plan_scale/lines
$PY $O/stage2.py $O/val_thorough_paper_6_2_a.json,$O/val_thorough_paper_6_2_b.json "all/0.125:0.25:0.5:1:2/6" $O/val_stage2c_paper_6_2.json > $O/val_stage2c_paper_6_2.log 2>&1
$PY $O/cache_plans.py large_400 5000,5001,5002 thorough $O/val_thorough_large_400.json > $O/val_thorough_large_400.log 2>&1
$PY $O/chain_cached.py $O/val_thorough_large_400.json $O/chain_thorough_large_400.json > $O/chain_thorough_large_400.log 2>&1
$PY $O/stage2.py $O/val_thorough_large_400.json "all+block/0.125:0.25:0.5:1:2/6" $O/val_stage2_large_400.json > $O/val_stage2_large_400.log 2>&1
