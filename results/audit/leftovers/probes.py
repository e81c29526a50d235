"""leftovers: one probe per defect, printed as one JSON record each (results/audit/leftovers).

``python probes.py WORKDIR OUT.jsonl`` probes the ``poc_env`` it imports; run through
``results/audit/export/run_main.py`` with ``POC_ENV_TREE`` set to an unpacked ``git archive
main`` it probes main's (the before), run directly this checkout's (the after). Subprocess
probes (a FIFO, a Ctrl-C, two ``main()`` calls) start the same ``poc_env`` (the child gets
``POC_ENV_TREE`` too). No timing is recorded.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import re
import subprocess
import sys
from itertools import pairwise
from pathlib import Path

HERE = Path(__file__).resolve()
RUN_MAIN = HERE.parents[1] / "export" / "run_main.py"


def test_module(rel: str):
    """A test module of this checkout by its path under tests/ (its helpers: one copy)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(Path(rel).stem, HERE.parents[3] / "tests" / rel)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def child(code: str, timeout: float = 120.0, lines: int = 3) -> dict:
    """``code`` run by a fresh interpreter importing the same ``poc_env`` as this process: its
    status and the last ``lines`` lines of its stderr."""
    path = Path(os.environ.get("PROBE_DIR", ".")) / "child.py"
    path.write_text(code, encoding="utf-8")
    cmd = [sys.executable, str(path)]
    if os.environ.get("POC_ENV_TREE"):
        cmd = [sys.executable, str(RUN_MAIN), str(path)]
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=False)
    except subprocess.TimeoutExpired:
        return {"rc": None, "blocked": f"no end within {timeout:g} s"}
    return {"rc": r.returncode, "stderr": r.stderr.strip().splitlines()[-lines:]}


def p1_merge(work: Path) -> dict:
    """A merge into an existing folder whose third rename fails (ENOSPC injected)."""
    from poc_env.io import atomic_dir

    dest = work / "merge"
    dest.mkdir()
    for name in ("a.txt", "b.txt"):
        (dest / name).write_text("old")
    real = os.replace

    def failing(src, dst, *a, **k):
        if os.fspath(dst).endswith("c.txt"):
            raise OSError(28, "No space left on device")
        return real(src, dst, *a, **k)

    os.replace = failing
    try:
        with contextlib.suppress(OSError), atomic_dir(dest) as stage:
            for name in ("a.txt", "b.txt", "c.txt", "d.txt"):
                (stage / name).write_text("new")
    finally:
        os.replace = real
    return {"after the failure": {p.name: p.read_text() for p in sorted(dest.iterdir())}}


def _say(fn, *args, **kwargs):
    """(result, printed text, error text)."""
    out = io.StringIO()
    try:
        with contextlib.redirect_stdout(out):
            return fn(*args, **kwargs), out.getvalue(), None
    except Exception as err:  # a probe records what happened
        return None, out.getvalue(), f"{type(err).__name__}: {err}"


def p2_nothing_reached(work: Path) -> dict:
    """``small`` with its airfield 80 km south: no UAV reaches any mass; each format."""
    from poc_env.agents.mission.export import export_plan
    from poc_env.agents.mission.plan import write_plan
    from poc_env.agents.planning.planner import make_plan
    from poc_env.config import load_scenario

    data = load_scenario("small").to_dict()
    data["airfields"] = [{"name": "A", "position_km": [20, -80]}]
    plan = make_plan(
        load_scenario(data), planner="allocation", refine=0, origin_deg=(45.75, 126.65)
    )
    write_plan(plan, work / "none.json")
    rec = {"reason": plan["reason"]}
    for fmt in ("qgc", "kml", "geojson", "html"):
        files, _, err = _say(export_plan, work / "none.json", fmt, out_dir=work / f"none_{fmt}")
        if err:
            rec[fmt] = "refused: " + err.split(";")[0]
        elif fmt == "geojson":
            doc = json.loads(files[0].read_text())
            zero = [f for f in doc["features"] if f["properties"].get("kind") == "route"
                    and len({tuple(c) for c in f["geometry"]["coordinates"]}) == 1]  # fmt: skip
            rec[fmt] = f"written: {len(zero)} zero-length routes"
        else:
            rec[fmt] = f"written: {len(files)} file(s)"
    return rec


def _jumps(lons: list[float]) -> int:
    return sum(abs(b - a) > 180.0 for a, b in pairwise(lons))


def p3_antimeridian(work: Path) -> dict:
    """An area imported at 179.6-179.98 E, its airfield at 179.97 W."""
    from poc_env.agents.mission.export import export_plan

    fiji = test_module("mission/test_export_audit.py")._plan_imported_at_the_antimeridian(work)
    rec = {}
    (g,), _, _ = _say(export_plan, fiji, "geojson", out_dir=work / "fg")
    feats = json.loads(g.read_text())["features"]
    lines = []
    for f in feats:
        c = f["geometry"]["coordinates"]
        while c and isinstance(c[0], list) and isinstance(c[0][0], list):
            lines += c[1:] if isinstance(c[0][0][0], list) else []
            c = c[0]
        lines.append(c)
    rec["geojson lines or rings jumping 180 -> -180"] = sum(
        _jumps([p[0] for p in ln]) > 0 for ln in lines if ln and isinstance(ln[0], list)
    )
    rec["geojson Multi* geometries"] = sum(f["geometry"]["type"].startswith("Multi") for f in feats)
    files, _, _ = _say(export_plan, fiji, "kml", out_dir=work / "fk")
    text = next(f for f in files if f.suffix == ".kml").read_text()
    coords = re.findall(r"<coordinates>([^<]*)</coordinates>", text)
    rec["kml coordinates jumping"] = sum(
        _jumps([float(t.split(",")[0]) for t in c.split()]) > 0 for c in coords
    )
    box = {k: float(v) for k, v in re.findall(r"<(east|west)>([^<]*)</", text)}
    rec["kml prior box west, east"] = [box.get("west"), box.get("east")]
    (h,), _, _ = _say(export_plan, fiji, "html", out_dir=work / "fh")
    m = re.search(r'id="plan-data">(.*?)</script>', h.read_text(), re.S)
    data = json.loads(m.group(1)) if m else {}
    rows = [seg for u in data.get("uavs", []) for seg in [*u["transit"], u["search"]] if seg]
    rows += [z["latlon"] for z in data.get("operating_area", [])]
    rec["html lines jumping"] = sum(_jumps([p[1] for p in r]) > 0 for r in rows)
    rec["html prior bounds west, east"] = [
        b[1] for b in (data.get("overlay") or {}).get("bounds", [])
    ]
    return rec


def _first_plan(work: Path) -> Path:
    from poc_env.cli import main

    p1 = work / "p1.json"
    if not p1.exists():
        with contextlib.redirect_stdout(io.StringIO()):
            assert main(["plan", "--scenario", "small", "--planner", "allocation", "--origin",
                         "46.5,7.9", "--quiet", "--out", str(p1)]) == 0  # fmt: skip
    return p1


def _cli(argv: list[str]) -> dict:
    from poc_env.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main(argv)
    lines = [ln for ln in (out.getvalue() + err.getvalue()).splitlines()
             if ln.startswith(("error:", "warning:"))]  # fmt: skip
    return {"rc": rc, "said": [ln[:160] for ln in lines]}


def p4_tracks(work: Path) -> dict:
    """replan with UAV 2's track ending at a field ~100 km east; tracks in UTM 32N (a crs)."""
    p1 = _first_plan(work)
    plan = json.loads(p1.read_text())
    helpers = test_module("planning/test_replan.py")  # the routes written as tracks
    feats = helpers._tracks(work / "div.geojson", plan)
    feats[1]["geometry"]["coordinates"].append([9.2, 46.6])
    (work / "div.geojson").write_text(json.dumps({"type": "FeatureCollection", "features": feats}))
    rec = {"diverted": _cli(["replan", "--plan", str(p1), "--tracks", str(work / "div.geojson"),
                             "--out", str(work / "n_div.json")])}  # fmt: skip
    helpers._utm_tracks(work / "utm.geojson", plan)
    rec["utm crs"] = _cli(["replan", "--plan", str(p1), "--tracks", str(work / "utm.geojson"),
                           "--out", str(work / "n_utm.json")])  # fmt: skip
    for key, name in (("diverted", "n_div.json"), ("utm crs", "n_utm.json")):
        if (work / name).exists():
            rec[key]["searched_pos"] = round(
                json.loads((work / name).read_text())["searched_pos"], 4
            )
    return rec


def p5_cli(work: Path) -> dict:
    """scenario import's file errors, a FIFO as --tracks, two main() calls, an early Ctrl-C."""
    ring = [[126.0, 45.3], [127.2, 45.3], [127.2, 46.1], [126.0, 46.1], [126.0, 45.3]]
    area = {"type": "Feature", "properties": {},
            "geometry": {"type": "Polygon", "coordinates": [ring]}}  # fmt: skip
    field = {"type": "Feature", "properties": {"name": "A"},
             "geometry": {"type": "Point", "coordinates": [126.5, 45.2]}}  # fmt: skip
    (work / "ia.geojson").write_text(json.dumps(area))
    (work / "if.geojson").write_text(json.dumps(field))
    base = ["scenario", "import", str(work / "ia.geojson"), "--airfields", str(work / "if.geojson"),
            "--out", str(work / "s.yaml")]  # fmt: skip
    rec = {"missing --no-fly": _cli([*base, "--no-fly", str(work / "nope.geojson")])}
    (work / "empty.geojson").write_text("")
    real = os.open

    def no_permission(path, flags, *a, **k):
        if os.fspath(path).endswith("empty.geojson"):
            raise PermissionError(13, "Permission denied", os.fspath(path))
        return real(path, flags, *a, **k)

    os.open = no_permission
    try:
        rec["zero-size, no permission, --no-fly"] = _cli(
            [*base, "--no-fly", str(work / "empty.geojson")]
        )
    finally:
        os.open = real
    p1 = _first_plan(work)
    fifo = work / "fifo.geojson"
    if not fifo.exists():
        os.mkfifo(fifo)
    rec["FIFO as --tracks"] = child(
        "from poc_env.cli import main\nimport sys\n"
        f"sys.exit(main(['replan', '--plan', {str(p1)!r}, '--tracks', {str(fifo)!r}, '--out', "
        f"{str(work / 'n_fifo.json')!r}]))\n",
        timeout=30.0,
    )
    rec["two main() calls"] = child(
        "import contextlib, io, sys\nfrom poc_env import limits\nfrom poc_env.cli import main\n"
        "seen = []\nreal = limits.memory_limit_bytes\n"
        "def spy():\n    seen.append(real() / 2**30)\n    return real()\n"
        "limits.memory_limit_bytes = spy\n"
        f"base = ['plan', '--scenario', 'small', '--planner', 'allocation', '--quiet', '--out', "
        f"{str(work / 'mm.json')!r}]\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    main(['--max-memory-gb', '3', *base]); first = sorted(set(seen)); seen.clear()\n"
        "    main(base); second = sorted(set(seen))\n"
        "print(f'GiB seen: first call {first}, second call (no option) {second}',\n"
        "      file=sys.stderr)\n"
    )
    kick = test_module("e2e/test_cli_audit.py").KICK_WHILE_IMPORTING
    rec["Ctrl-C while importing"] = child(kick)
    return rec


def p6_glide(work: Path) -> dict:
    """A plan landing at the foot of a 150 m/km slope: glide warnings per command."""
    import yaml

    tt = test_module("mission/test_terrain.py")
    data = tt._scenario(None, terrain={"elevation_m": tt._slope(150.0), "cell_km": 1.0,
                                       "origin_km": [-40, -30]})  # fmt: skip
    (work / "steep.yaml").write_text(yaml.safe_dump(data))
    rec = {}
    cmds = {"plan": ["plan", "--scenario", str(work / "steep.yaml"), "--planner", "allocation",
                     "--quiet", "--out", str(work / "steep.json")]}  # fmt: skip
    for fmt in ("qgc", "kml", "geojson", "html"):
        cmds[f"export {fmt}"] = ["export", str(work / "steep.json"), "--format", fmt, "--out",
                                 str(work / f"steep_{fmt}")]  # fmt: skip
    for name, argv in cmds.items():
        code = f"import sys\nfrom poc_env.cli import main\nsys.exit(main({argv!r}))\n"
        r = child(code, lines=1000)
        err = "\n".join(r["stderr"])
        said = [ln for ln in err.splitlines() if "final glide of" in ln]
        rec[name] = {"rc": r["rc"], "glide lines": len(said),
                     "format": said[0][:60] if said else None}  # fmt: skip
    return rec


def main() -> int:
    work, out = Path(sys.argv[1]), Path(sys.argv[2])
    work.mkdir(parents=True, exist_ok=True)
    os.environ["PROBE_DIR"] = str(work)
    records = []
    for probe in (p1_merge, p2_nothing_reached, p3_antimeridian, p4_tracks, p5_cli, p6_glide):
        sub = work / probe.__name__
        sub.mkdir(exist_ok=True)
        try:
            result = probe(sub)
        except Exception as err:  # a probe records what happened
            result = {"probe failed": f"{type(err).__name__}: {err}"[:300]}
        records.append({"probe": probe.__name__, "doc": probe.__doc__, "result": result})
        print(json.dumps(records[-1]), flush=True)
    out.write_text("".join(json.dumps(r) + "\n" for r in records))
    return 0


if __name__ == "__main__":
    sys.exit(main())
