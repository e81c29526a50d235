"""Odd strings through every YAML the project writes, reloaded and compared (cli-audit).

``python results/audit/cli/probe_yaml.py INPUTS`` (INPUTS: the kill harness's inputs folder,
with the Harbin layers of docs/missions.md), run in a scratch folder; one JSON line per case:
``[where, string, OK | MISMATCH got | refused status | RELOAD FAILS, message]``.
"""

import contextlib
import io
import json
import sys
from pathlib import Path

from poc_env.cli import main
from poc_env.config import load_scenario, save_scenario

ODD = ["yes", "null", "~", "1e3", "0x10", "a: b", "#x", "- x", "'q'", '"dq"', "a\nb", "  lead",
       "trail  ", "名前", "x" * 300, "{a: 1}", "[1, 2]", "*alias", "&anchor", "!tag", "%d", "@at",
       "`b`", "", "\t", "a\u2028b", "\x85", "NaN", ".inf", "2024-01-01", "08", "True"]  # fmt: skip


def _point(name: str, lon: float, lat: float) -> dict:
    point = {"type": "Point", "coordinates": [lon, lat]}
    return {"type": "Feature", "properties": {"name": name}, "geometry": point}


def scenario_fields(res: list) -> None:
    """The scenario's name and description through save_scenario -> load_scenario."""
    for s in ODD:
        for key in ("name", "description"):
            try:
                sc = load_scenario("small", {key: s})
            except Exception as e:  # a refusal is a result too
                res.append((f"scenario.{key}", s, "refused", str(e)[:100]))
                continue
            save_scenario(sc, "sc.yaml")
            try:
                back = load_scenario("sc.yaml")
            except Exception as e:
                res.append((f"scenario.{key}", s, "RELOAD FAILS", str(e)[:120]))
                continue
            ok = back == sc and getattr(back, key) == s
            res.append((f"scenario.{key}", s, "OK" if ok else f"MISMATCH {getattr(back, key)!r}",
                        ""))  # fmt: skip


def imported_names(res: list, inp: Path) -> None:
    """Airfield and no-fly zone names through scenario import -> load_scenario."""
    Path("area.geojson").write_text((inp / "area.geojson").read_text())
    for s in ODD:
        fields = {"type": "FeatureCollection",
                  "features": [_point(s, 126.25, 45.623), _point("B", 126.95, 45.25)]}  # fmt: skip
        zones = json.loads((inp / "zones.geojson").read_text())
        zones["features"][0]["properties"]["name"] = s
        Path("f.geojson").write_text(json.dumps(fields))
        Path("z.geojson").write_text(json.dumps(zones))
        for which in ("airfield", "zone"):
            layer = "f.geojson" if which == "airfield" else str(inp / "fields.geojson")
            args = ["scenario", "import", "area.geojson", "--airfields", layer, "--out", "h.yaml"]
            if which == "zone":
                args += ["--no-fly", "z.geojson"]
            for q in Path(".").glob("h.*"):
                q.unlink()
            err = io.StringIO()
            with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
                code = main(args)
            if code != 0:
                res.append((f"import {which} name", s, f"refused {code}",
                            err.getvalue().strip()[-120:]))  # fmt: skip
                continue
            sc = load_scenario("h.yaml")
            names = (
                [a.name for a in sc.airfields] if which == "airfield" else list(sc.map.no_fly_names)
            )
            res.append((f"import {which} name", s, "OK" if s in names else f"MISMATCH {names!r}",
                        ""))  # fmt: skip


if __name__ == "__main__":
    results: list = []
    scenario_fields(results)
    imported_names(results, Path(sys.argv[1]))
    for r in results:
        print(json.dumps(r, ensure_ascii=False))
