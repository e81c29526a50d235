# The walkthrough's sortie 1 without --no-fly (the page's "without the zone" figure), both
# efforts. Run in an empty folder with the repository's venv first on PATH and REPO set:
#   export PATH=$REPO/.venv/bin:$PATH; bash $REPO/results/mission/i24-walkstandard/nozone.sh
set -e
python - <<'PY'
import os, sys
from pathlib import Path
sys.path[:0] = [os.environ["REPO"] + "/tests/e2e"]
import test_sar_walkthrough as W
setup, _ = W._blocks()
W._run(setup, Path("."))
W._terrain_test()._dem(Path("dem.tif"))
PY
poc-env scenario import area.geojson --prior prior.csv --airfields airfield.geojson \
    --dem dem.tif --base small --out alps_nz.yaml
for effort in default standard; do
  poc-env plan --scenario alps_nz.yaml --planner allocation --effort $effort \
      --overrides uav.max_altitude_m=6000 --quiet --out nz_$effort.json
done
