P=/work/wt/i28-audit/.venv/bin
export OMP_NUM_THREADS=1
ev(){ echo "### $1 on $2"; $P/poc-env evaluate --task $2 --policies $1 --episodes 2 --seed 987654 --quiet 2>&1 | grep -E "^(ppo|rllib|note|error)" ; }
ev ppo:ppo_heading_individual_paper_6_2 UAVSearch-Paper62-Random-Heading-v0
ev ppo:ppo_heading_paper_6_2 UAVSearch-Paper62-Random-Heading-v0
ev ppo:ppo_increments_individual_paper_6_2 UAVSearch-Paper62-Random-Increments-v0
ev ppo:ppo_increments_paper_6_2 UAVSearch-Paper62-Random-Increments-v0
ev ppo:ppo_pilot_paper_6_2 UAVSearch-Paper62-Random-Heading-v0
ev ppo:ppo_set_anysize UAVSearch-Paper62-Random-Set-Heading-v1
ev ppo:ppo_set_increments_anysize UAVSearch-Paper62-Random-Set-Increments-v0
ev ppo:ppo_drift_small UAVSearch-Small-Drift-Heading-v1
ev rllib:rllib_heading_paper_6_2 UAVSearch-Paper62-Random-Heading-v0
ev ppo:ppo_set_anysize UAVSearch-Wide-N24-Random-Set-Heading-v1
ev ppo:ppo_set_increments_anysize UAVSearch-Wide-N24-Random-Set-Increments-v0
