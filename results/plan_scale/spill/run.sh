#!/bin/sh
# The records of results/plan_scale/spill (one thread each, from the repository root). The
# large_400 priors ran as three processes (0; 1-12; 13-24), the last two at the same time.
set -e
export OMP_NUM_THREADS=1
S=results/plan_scale/spill
python $S/spill.py groups large_400 5000 5003 $S/groups_large_400.json > $S/groups_large_400.log
python $S/spill.py bounds paper_6_2 0 50 $S/paper_6_2.json > $S/paper_6_2.log
python $S/spill.py bounds large_400 0 1 $S/large_400_0.json > $S/large_400_0.log
python $S/spill.py bounds large_400 1 13 $S/large_400_a.json > $S/large_400_a.log &
python $S/spill.py bounds large_400 13 25 $S/large_400_b.json > $S/large_400_b.log
wait
python $S/spill.py variants large_400 5000 5001 $S/variants_large_400.json > $S/variants_large_400.log
python $S/spill.py table $S/paper_6_2.json $S/large_400_0.json $S/large_400_a.json \
  $S/large_400_b.json $S/groups_large_400.json $S/variants_large_400.json > $S/table.md
