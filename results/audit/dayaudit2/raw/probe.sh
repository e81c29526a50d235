# usage: probe.sh NAME OUTDIR cmd...  -> logs rc, stderr tail, files written in OUTDIR (new)
name=$1; out=$2; shift 2
mkdir -p $out; before=$(find $out -type f | sort)
"$@" > logs/$name.log 2>&1; rc=$?
after=$(find $out -type f | sort)
new=$(comm -13 <(echo "$before") <(echo "$after") | tr '\n' ' ')
echo "== $name rc=$rc new_files=[$new]"; echo "   \$ $*" | sed "s#/tmp/da2/venv/bin/##"; grep -i "error\|warning\|note" logs/$name.log | head -4 | sed 's/^/   /'
