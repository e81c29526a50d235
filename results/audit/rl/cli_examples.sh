set -x
P=/work/wt/i28-audit/.venv/bin
export OMP_NUM_THREADS=1
$P/poc-env train --task poc_env/UAVSearch-Small-Heading-v1 --total-timesteps 20000 --run-dir runs/small --no-progress; echo RC=$?
$P/poc-env train --resume runs/small --no-progress; echo RC=$?
$P/poc-env train --from-card ppo_set_increments_anysize --seed 2 --run-dir runs/s2 --total-timesteps 2000 --no-progress; echo RC=$?
$P/poc-env train --scenario small --overrides episode.horizon_steps=40 --recipe pilot --total-timesteps 4096 --n-envs 2 --run-dir runs/pilot --no-progress; echo RC=$?
$P/poc-env train --engine rllib --task poc_env/UAVSearch-Small-Heading-v1 --total-timesteps 8000 --num-env-runners 0 --run-dir runs/rllib --no-progress; echo RC=$?
$P/poc-env evaluate --task poc_env/UAVSearch-Small-Heading-v1 --policies ppo:runs/small,rllib:runs/rllib,greedy_bayes --episodes 3 --baseline greedy_bayes --out out/ev_small --quiet; echo RC=$?
$P/poc-env summarise out/ev_small; echo RC=$?
$P/poc-env curve runs/small; echo RC=$?
$P/poc-env curve runs/rllib; echo RC=$?
ls -la runs/small runs/rllib out/ev_small
P=/work/wt/i28-audit/.venv/bin
export OMP_NUM_THREADS=1
set -x
$P/poc-env evaluate --task poc_env/UAVSearch-Small-Heading-v1 --policies ppo:runs/small,rllib:runs/rllib,greedy_bayes --episodes 3 --baseline greedy_bayes --out out/ev_small --quiet; echo RC=$?
$P/poc-env summarise out/ev_small; echo RC=$?
$P/poc-env evaluate --task poc_env/UAVSearch-Small-Random-Heading-v1 --policies ppo:runs/pilot --episodes 1 --quiet; echo RC=$?
P=/work/wt/i28-audit/.venv/bin
export OMP_NUM_THREADS=1
set -x
time $P/poc-env train --from-card ppo_set_increments_anysize --seed 2 --run-dir runs/s2b --total-timesteps 512 --bc-episodes 1 --bc-epochs 1 --no-progress; echo RC=$?
$P/poc-env evaluate --task UAVSearch-Wide-N6-Random-Set-Increments-v0 --policies ppo:runs/s2b --episodes 1 --quiet; echo RC=$?
