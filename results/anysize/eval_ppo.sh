#!/bin/bash
# The learned rows on the evaluation stream (seeds 28000-28049, never used in training or
# selection), then joined with the planners' rows of the same seeds (base_*):
#   results/anysize/eval_ppo.sh "ppo:ppo_set_anysize" "ppo:SPEC_N6" "ppo:SPEC_N12" "ppo:SPEC_N24"
set -euo pipefail
G=$1; S6=${2:-}; S12=${3:-}; S24=${4:-}
E="poc-env evaluate --episodes 50 --seed 28000 --quiet"
P=UAVSearch-Paper62-Random-Set-Heading-v1
D=results/anysize
$E --task $P --policies "$G" --out $D/ppo_paper62
$E --task $P --overrides map.width_km=150 map.height_km=200 --policies "$G" --out $D/ppo_tall
$E --task UAVSearch-Wide-N6-Random-Set-Heading-v1 --policies "$G${S6:+,$S6}" --out $D/ppo_wide_n6
$E --task UAVSearch-Wide-N12-Random-Set-Heading-v1 --policies "$G${S12:+,$S12}" --out $D/ppo_wide_n12
$E --task UAVSearch-Wide-N24-Random-Set-Heading-v1 --policies "$G${S24:+,$S24}" --out $D/ppo_wide_n24
for c in paper62 tall wide_n6 wide_n12 wide_n24; do
  python $D/join.py $D/ppo_$c $D/base_$c --out $D/eval_$c --baseline allocation_plan
done
