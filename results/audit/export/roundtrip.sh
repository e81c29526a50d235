# replan with no tracks, then with the exported KML, then GeoJSON, as tracks: the same "found"?
P=/work/wt/export-audit/.venv/bin/poc-env
rt() { sc="$1"; pl="$2"; d="$3"; stem="$4"; shift 4
  for t in none kml geojson; do
    case $t in none) a="";; kml) a="--tracks $d/$stem.kml";; geojson) a="--tracks $d/$stem.geojson";; esac
    echo "$pl $t: $($P replan --scenario $sc --plan $pl $a "$@" --out /tmp/export-audit/p/rt.json 2>&1 | grep -E 'sortie 2|rror' | head -2)"
  done; }
rt small small.json outB/small small
rt chile/chile.yaml chile/plan.json outB/chile_plan plan
rt n60/n60.yaml n60/plan.json outB/n60_plan plan
rt paper_6_2 paper.json outB/paper paper
rt paper_6_2 u24.json outB/u24 u24   # replan takes the plan's 24 UAVs (no --uavs)
rt alps/alps.yaml alps/p1.json outB/alps_p1 p1 --overrides uav.max_altitude_m=6000
