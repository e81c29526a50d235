"""The HTML map report: one self-contained page, drawn by a real headless browser.

The browser test runs Debian's chromium offline (every host name resolves to nothing) and
checks the page's ``data-drawn`` marker, the screenshot (the prior overlay's colours and the
first route's colour inside the map) and the console log. Without chromium it is skipped,
except when ``CI`` is set: then it fails and says how to install chromium.
"""

from __future__ import annotations

import base64
import io
import json
import math
import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from poc_env.agents.mission.crs import to_geographic
from poc_env.agents.mission.export import export_plan
from poc_env.agents.mission.formats.report import ROUTE_COLOURS, expected_layers
from poc_env.agents.mission.overlay import (
    ALPHA_RANGE,
    colorize,
    plan_prior,
    png_bytes,
    warp_prior,
)
from poc_env.agents.mission.plan import load_plan, write_plan
from poc_env.agents.planning.planner import make_plan
from poc_env.cli import main
from poc_env.errors import ConfigError

ORIGIN = (45.75, 126.65)
#: Leaflet's map background (leaflet.css ``.leaflet-container``): what an offline map shows.
LEAFLET_BG = np.array([221, 221, 221])


@pytest.fixture(scope="module")
def small_plan(tmp_path_factory):
    """A quick plan on the small scenario with a CRS (3 UAVs, no no-fly zones)."""
    path = tmp_path_factory.mktemp("report") / "plan.json"
    plan = make_plan("small", popsize=8, maxiter=3, seed=0, origin_deg=ORIGIN)
    write_plan(plan, path)
    return path


def _payload(page: str) -> dict:
    m = re.search(r'<script type="application/json" id="plan-data">(.*?)</script>', page, re.S)
    assert m, "the page embeds its data"
    return json.loads(m.group(1))


def _png(uri: str) -> np.ndarray:
    from PIL import Image

    head = "data:image/png;base64,"
    assert uri.startswith(head)
    return np.asarray(Image.open(io.BytesIO(base64.b64decode(uri[len(head) :]))).convert("RGBA"))


def test_page_is_one_self_contained_file(small_plan, tmp_path):
    (out,) = export_plan(small_plan, "html", out_dir=tmp_path)
    assert out.name == "plan.html" and sorted(p.name for p in tmp_path.iterdir()) == ["plan.html"]
    page = out.read_text(encoding="utf-8")
    plan = load_plan(small_plan)
    # nothing loaded from elsewhere: no external script, stylesheet or image; CSS urls inlined
    assert not re.search(r"<script[^>]*\bsrc=", page)
    assert "<link" not in page
    assert not re.search(r"\bsrc=[\"'](?!data:)", page)
    assert set(re.findall(r"url\((?!data:)([^)]*)\)", page)) <= {"#default#VML"}
    assert "L.map(" in page and "Leaflet 1.9.4" in page  # the vendored library is inlined
    data = _payload(page)
    assert len(data["uavs"]) == len(plan["uavs"]) == 3
    assert [u["id"] for u in data["uavs"]] == [str(u["id"]) for u in plan["uavs"]]
    assert data["tiles"]["url"].startswith("https://tile.openstreetmap.org/")
    assert data["overlay"] is not None and len(data["airfields"]) == 1
    for u, pu in zip(data["uavs"], plan["uavs"]):
        assert u["colour"] in ROUTE_COLOURS
        # transit legs: take-off -> first search point, last search point -> landing
        assert len(u["transit"]) == 2 and len(u["search"]) == len(pu["waypoints_m"])
        (lat, lon), *_ = to_geographic([pu["takeoff_m"]], plan["crs"])
        assert u["transit"][0][0] == pytest.approx([lat, lon], abs=1e-6)
    # the per-UAV table is static HTML: one row per UAV with its POS
    table = page[page.index('<table id="uav-table">') : page.index("</table>")]
    assert table.count("<tr>") == 1 + len(plan["uavs"])
    for u in plan["uavs"]:
        assert f"<td>{100 * u['pos']:.2f}</td>" in table


def test_png_writer_round_trip():
    from PIL import Image

    rgba = np.random.default_rng(3).integers(0, 256, (7, 11, 4), dtype=np.uint8)
    back = np.asarray(Image.open(io.BytesIO(png_bytes(rgba))))
    np.testing.assert_array_equal(back, rgba)
    with pytest.raises(ConfigError, match="RGBA"):
        png_bytes(np.zeros((3, 3, 3), np.uint8))


def test_colormap_ends_and_alpha():
    c = colorize(np.array([0.0, 1.0]))
    assert c[0].tolist() == [255, 255, 204, ALPHA_RANGE[0]]
    assert c[1].tolist() == [128, 0, 38, ALPHA_RANGE[1]]


@pytest.mark.parametrize("rows", ["mercator", "latitude"])
def test_overlay_pixels_show_the_cell_under_them(small_plan, rows):
    """Each cell centre, projected to lat/lon by pyproj and located in the image by the rows'
    spacing (Web Mercator for Leaflet, latitude for KML), has that cell's colour."""
    plan = load_plan(small_plan)
    ov, note = plan_prior(plan, small_plan)
    assert ov is not None, note
    rgba, (s, w, n, e) = warp_prior(ov, plan["crs"], rows)
    h, wpx = rgba.shape[:2]
    peak = ov.values.max()

    def y(lat):
        return (
            math.log(math.tan(math.pi / 4 + math.radians(lat) / 2)) if rows == "mercator" else lat
        )

    centres = ov.grid.centers.reshape(-1, 2)
    for (lat, lon), (x_m, y_m) in zip(to_geographic(centres, plan["crs"]), centres):
        r = int((y(n) - y(lat)) / (y(n) - y(s)) * h)
        c = int((lon - w) / (e - w) * wpx)
        j, i = ov.grid.cell_of(np.array([x_m, y_m]))
        np.testing.assert_array_equal(rgba[r, c], colorize(ov.values[j, i] / peak))
    assert rgba[0, 0, 3] == 0 or rgba[-1, -1, 3] == 0 or (rgba[..., 3] > 0).all()
    assert (rgba[..., 3] == 0).sum() < 0.1 * h * wpx  # the box is tight around the grid


def test_prior_is_rebuilt_only_when_the_plan_agrees(small_plan, tmp_path):
    plan = load_plan(small_plan)
    ov, note = plan_prior(plan, small_plan)
    assert ov is not None and ov.values.shape == ov.grid.shape and "small" in note
    moved = dict(plan, airfields=[{"name": "A", "position_m": [0.0, 0.0]}])
    ov2, note2 = plan_prior(moved, small_plan)
    assert ov2 is None and "airfields" in note2
    ov3, note3 = plan_prior(dict(plan, scenario="nowhere"), small_plan)
    assert ov3 is None and "nowhere" in note3
    given = np.ones(ov.grid.shape)
    ov4, _ = plan_prior(moved, small_plan, given)
    assert ov4 is not None and ov4.source == "given"
    with pytest.raises(ConfigError, match="prior"):
        plan_prior(plan, small_plan, np.ones((3, 3)))
    # a page without the overlay still draws the rest and says why
    path = tmp_path / "moved.json"
    path.write_text(json.dumps(moved))
    (out,) = export_plan(path, "html")
    page = out.read_text(encoding="utf-8")
    assert _payload(page)["overlay"] is None and "no prior overlay" in page


def test_export_html_of_a_custom_yaml_plan_finds_its_prior_or_says_why(tmp_path, capsys):
    """Issue 27: a plan made from a YAML scenario whose ``name:`` is not its file name
    (``custom.yaml`` holding ``name: harbin_day2``) records the file, so export draws the prior
    from it; with the file gone, the command line (not only the page) says which files it
    looked for and how to give it the scenario."""
    import poc_env

    src = tmp_path / "scenarios" / "custom.yaml"
    src.parent.mkdir()
    text = (Path(poc_env.__file__).parent / "configs" / "small.yaml").read_text()
    src.write_text(text.replace("name: small", "name: harbin_day2", 1))
    plan = tmp_path / "plans" / "plan.json"
    assert main(["plan", "--scenario", str(src), "--popsize", "8", "--maxiter", "3", "--quiet",
                 "--origin", "45.75,126.65", "--out", str(plan)]) == 0  # fmt: skip
    assert json.loads(plan.read_text())["scenario_file"] == str(src.resolve())
    capsys.readouterr()
    assert main(["export", str(plan), "--format", "html", "--out", str(tmp_path / "a")]) == 0
    said = capsys.readouterr().out
    assert "no prior overlay" not in said, said
    assert _payload((tmp_path / "a" / "plan.html").read_text())["overlay"] is not None
    src.rename(tmp_path / "elsewhere.yaml")
    assert main(["export", str(plan), "--format", "html", "--out", str(tmp_path / "b")]) == 0
    said = capsys.readouterr().out
    assert "note: no prior overlay" in said and str(src.resolve()) in said, said
    assert "beside the plan as harbin_day2.yaml" in said, said
    assert _payload((tmp_path / "b" / "plan.html").read_text())["overlay"] is None


def test_cli_html_and_bad_input(small_plan, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["export", str(small_plan), "--format", "html", "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["plan.html"]
    # no crs and no --origin: a clean error, nothing written
    plan = json.loads(small_plan.read_text())
    del plan["crs"]
    bare = tmp_path / "bare.json"
    bare.write_text(json.dumps(plan))
    capsys.readouterr()
    dest = tmp_path / "none"
    assert main(["export", str(bare), "--format", "html", "--out", str(dest)]) == 2
    err = capsys.readouterr().err
    assert "error: origin:" in err and "records no crs" in err
    assert not dest.exists() or not any(dest.iterdir())
    assert main(["export", str(small_plan), "--format", "htm", "--out", str(dest)]) == 2
    assert "html" in capsys.readouterr().err  # the allowed formats name html


def _chromium() -> str:
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        if os.environ.get("CI"):
            pytest.fail(
                "chromium is required in CI for the HTML report test: install it with "
                "`apt-get install -y chromium` (Debian/Ubuntu; `make` does this as root)"
            )
        pytest.skip("chromium is not installed (apt-get install -y chromium)")
    return exe


def _run_chromium(exe: str, page, *args: str) -> subprocess.CompletedProcess:
    cmd = [
        exe, "--headless", "--no-sandbox", "--disable-gpu", "--window-size=900,700",
        "--virtual-time-budget=3000", "--host-resolver-rules=MAP * ~NOTFOUND",
        "--no-first-run", "--disable-extensions", *args, page.as_uri(),
    ]  # fmt: skip
    return subprocess.run(cmd, capture_output=True, text=True, timeout=120, check=False)


def _browse(exe: str, page) -> tuple[int, np.ndarray, list[str]]:
    """(the page's data-drawn marker, the screenshot's map rows as (N, 3) RGB, console lines)."""
    from PIL import Image

    dom = _run_chromium(exe, page, "--dump-dom")
    assert dom.returncode == 0, dom.stderr[-2000:]
    m = re.search(r'<body[^>]*data-drawn="(\d+)"', dom.stdout)
    assert m, "the page's script did not finish drawing"
    shot = page.parent / "shot.png"
    run = _run_chromium(exe, page, f"--screenshot={shot}", "--enable-logging=stderr", "--v=0")
    assert run.returncode == 0 and shot.is_file(), run.stderr[-2000:]
    console = [
        line
        for line in run.stderr.splitlines()
        if (":CONSOLE" in line or "Uncaught" in line) and "tile.openstreetmap.org" not in line
    ]
    img = np.asarray(Image.open(shot).convert("RGB")).astype(int)
    # the map: the rows showing Leaflet's grey background (offline, no tiles)
    grey = (np.abs(img - LEAFLET_BG).max(axis=-1) == 0).sum(axis=1) > 100
    rows = np.flatnonzero(grey)
    assert rows.size > 200, "the map is not on the screenshot"
    return int(m.group(1)), img[rows.min() : rows.max() + 1].reshape(-1, 3), console


def _near(pixels: np.ndarray, hex_colour: str, tol: int) -> int:
    rgb = np.array([int(hex_colour[k : k + 2], 16) for k in (1, 3, 5)])
    return int((np.abs(pixels - rgb).max(axis=-1) <= tol).sum())


def test_headless_browser_draws_every_layer(small_plan, tmp_path):
    exe = _chromium()
    (page,) = export_plan(small_plan, "html", out_dir=tmp_path)
    plan = load_plan(small_plan)
    data = _payload(page.read_text(encoding="utf-8"))
    want = expected_layers(plan, overlay=True)
    assert want == 7  # prior, 3 routes, search areas, airfields, operating area
    drawn, mapped, console = _browse(exe, page)
    assert drawn == want
    assert console == [], console
    # the overlay's colours, as composited over the grey background
    ov = _png(data["overlay"]["url"]).reshape(-1, 4).astype(int)
    ov = np.unique(ov[ov[:, 3] > 0], axis=0)
    a = ov[:, 3:] / 255
    blended = np.round(a * ov[:, :3] + (1 - a) * LEAFLET_BG)
    near = np.abs(mapped[:, None, :] - blended[None, :, :]).max(axis=-1) <= 3
    hits = near.any(axis=1)
    assert hits.sum() > 2000, hits.sum()  # overlay pixels on screen
    assert np.unique(np.argmax(near[hits], axis=1)).size >= 10  # many of its colours
    # the first route's colour (opaque lines), inside the map (not the table's swatch)
    assert _near(mapped, ROUTE_COLOURS[0], 6) > 30
    assert _near(mapped, "#d00000", 6) == 0  # no no-fly zone in this plan


def test_headless_browser_draws_no_fly_zones_with_a_given_prior(small_plan, tmp_path):
    """A plan with a no-fly zone its scenario does not have: with the prior given, the page
    draws the overlay and the zone (red outline) too; one more layer."""
    exe = _chromium()
    plan = json.loads(small_plan.read_text())
    plan["no_fly_zones_m"] = [[[5e3, 5e3], [15e3, 5e3], [15e3, 15e3], [5e3, 15e3]]]
    path = tmp_path / "nfz.json"
    path.write_text(json.dumps(plan))
    ov, note = plan_prior(load_plan(path), path)
    assert ov is None and "no-fly zones" in note  # not rebuilt: the scenario has none
    ov, _ = plan_prior(load_plan(small_plan), small_plan)
    (page,) = export_plan(path, "html", prior=ov.values)
    assert _payload(page.read_text(encoding="utf-8"))["overlay"]["source"] == "given"
    drawn, mapped, console = _browse(exe, page)
    assert drawn == expected_layers(load_plan(path), overlay=True) == 8
    assert console == [], console
    assert _near(mapped, "#d00000", 6) > 30


def test_a_yaml_scenario_beside_the_plan_gives_the_overlay(tmp_path, monkeypatch):
    """``plan --scenario DIR/mine.yaml`` records ``mine``: the export finds ``mine.yaml`` beside
    the plan (from another folder), reads its file prior relative to the YAML, and draws it."""
    import yaml

    from poc_env.config import CONFIG_DIR

    data = yaml.safe_load((CONFIG_DIR / "small.yaml").read_text())
    data["name"] = "mine"
    data["map"]["prior"] = {"kind": "file", "file": "mine.npy"}
    folder = tmp_path / "work"
    folder.mkdir()
    prior = np.full((8, 8), 0.01)
    prior[6, 1] = 1.0  # one hot cell: north-west
    np.save(folder / "mine.npy", prior / prior.sum())
    (folder / "mine.yaml").write_text(yaml.safe_dump(data))
    plan = make_plan(str(folder / "mine.yaml"), popsize=8, maxiter=2, origin_deg=ORIGIN)
    assert plan["scenario"] == "mine"
    write_plan(plan, folder / "plan.json")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    (page,) = export_plan(folder / "plan.json", "html")
    ov = _payload(page.read_text(encoding="utf-8"))["overlay"]
    assert ov is not None and "mine" in ov["source"]
    img = _png(ov["url"])
    hot = np.unravel_index(np.argmax(img[..., 3]), img.shape[:2])
    # the most opaque pixel lies in the north-west of the image (row 6 of 8 from the south)
    assert hot[0] < img.shape[0] / 2 and hot[1] < img.shape[1] / 2


def test_overlay_ramp_is_matplotlibs_ylorrd_data():
    """The overlay's colour anchors are matplotlib's YlOrRd data (every other of its nine
    ColorBrewer classes), kept as a table so the core install needs no matplotlib."""
    mpl = pytest.importorskip("matplotlib")
    from poc_env.agents.mission.overlay import COLORMAP

    seg = mpl.colormaps["YlOrRd"]._segmentdata
    rgb = np.array([[seg[c][k][1] for c in ("red", "green", "blue")] for k in range(0, 9, 2)])
    np.testing.assert_array_equal(COLORMAP, np.round(255 * rgb))


def test_html_page_escapes_every_plan_string(tmp_path):
    """Autoescaping template: markup in the scenario name is text in the title, the summary
    and the note, and \\u003c-escaped in the script data; html.parser finds no injected tag."""
    from html.parser import HTMLParser

    from poc_env.agents.mission.formats.report import html_report

    class Tags(HTMLParser):
        tags: list = []

        def handle_starttag(self, tag, attrs):
            self.tags.append(tag)

    plan = {
        "schema": 1, "scenario": "<x-evil>&'\"</script>", "seed": 1, "map_source": "builtin",
        "optimizer": {"name": "<x-evil>", "settings": {}}, "runtime_s": 0.4, "posc": 0.3,
        "upper_bound": 0.5,
        "uavs": [{"id": 1, "rectangle": None, "spacing_m": 5e3, "takeoff_m": [0.0, 0.0],
                  "landing_m": [0.0, 0.0], "waypoints_m": [[1e3, 1e3], [2e3, 1e3]],
                  "track_length_m": 1e3, "flight_time_s": 60.0, "pod": 0.5, "poc": 0.5,
                  "pos": 0.25, "feasible": True}],
    }  # fmt: skip
    page = html_report(plan, ORIGIN, None, "<x-evil> note", 1000.0, "home", 0.0)
    p = Tags()
    p.feed(page)
    assert "x-evil" not in p.tags and p.tags.count("script") == 3
    assert "&lt;x-evil&gt;&amp;" in page and "\\u003cx-evil>" in page


def test_a_route_through_a_zone_is_flagged_by_every_viewing_format(small_plan, tmp_path, capsys):
    """Audit i24 (issue 24: "KML, GeoJSON and HTML export the crossing routes without a
    word"): a plan.json edited by hand so that a route crosses a no-fly zone. The QGC export
    refuses it (the exclusion geofence); GeoJSON, KML and the HTML report are still written,
    to show the officer the route, but each says so on the console, and the report's page
    says so too, with the same words as the QGC refusal."""
    plan = json.loads(small_plan.read_text())
    x, y = plan["uavs"][0]["waypoints_m"][1]
    plan["no_fly_zones_m"] = [[[x - 500, y - 500], [x + 500, y - 500], [x + 500, y + 500],
                               [x - 500, y + 500]]]  # fmt: skip
    plan["no_fly_zone_names"] = ["R-9"]
    path = tmp_path / "edited.json"
    path.write_text(json.dumps(plan))
    with pytest.raises(ConfigError, match=r"outside no-fly zone 0 \('R-9'\)"):
        export_plan(path, "qgc", out_dir=tmp_path / "q")
    for fmt in ("geojson", "kml", "html"):
        files = export_plan(path, fmt, out_dir=tmp_path / fmt)
        out = capsys.readouterr().err
        assert "warning: plan.uavs[0]: got 1; allowed: a mission outside no-fly zone 0 ('R-9')" in (
            out
        ), fmt
        if fmt == "html":
            assert "a mission outside no-fly zone 0 (&#39;R-9&#39;)" in files[0].read_text()
    export_plan(small_plan, "html", out_dir=tmp_path / "clean")
    assert "warning" not in capsys.readouterr().err


def test_headless_browser_draws_routes_above_zones_and_areas(small_plan, tmp_path):
    """Audit i24: the page drew the search areas, airfields, no-fly zones and the operating area
    after (above) the routes, so a zone's red fill tinted the route under it (and the areas
    took the mouse over their routes). Drawn now as a map is read: the ground (terrain,
    prior), the areas (operating area, zones, search areas), the routes, the airfields on
    top. Checked on screen: UAV 1's route shows its own colour as much under a zone laid
    over its whole search pattern as beside a small zone in a corner."""
    exe = _chromium()
    plan = json.loads(small_plan.read_text())
    wps = np.array(plan["uavs"][0]["waypoints_m"])
    (x0, y0), (x1, y1) = wps.min(axis=0) - 1000, wps.max(axis=0) + 1000
    ox0, oy0 = np.array(plan["operating_area_m"]).min(axis=0) + 1000
    zones = {
        "over": [[x0, y0], [x1, y0], [x1, y1], [x0, y1]],
        "corner": [[ox0, oy0], [ox0 + 2000, oy0], [ox0 + 2000, oy0 + 2000], [ox0, oy0 + 2000]],
    }
    seen = {}
    for name, zone in zones.items():
        plan["no_fly_zones_m"] = [[[float(a), float(b)] for a, b in zone]]
        path = tmp_path / name / "p.json"
        path.parent.mkdir()
        path.write_text(json.dumps(plan))
        (page,) = export_plan(path, "html", out_dir=path.parent)
        drawn, mapped, console = _browse(exe, page)
        assert console == [], console
        assert drawn == expected_layers(load_plan(path), overlay=False)  # no prior: edited
        seen[name] = _near(mapped, ROUTE_COLOURS[0], 6)
    assert seen["corner"] > 30
    assert seen["over"] >= 0.9 * seen["corner"], seen


def test_every_route_is_labelled_on_the_map(small_plan, tmp_path):
    """Audit i24: the page has 8 route colours for up to 64 UAVs (a 24-UAV fleet: three
    routes a colour), and a route was named only by a tooltip on hover, so a printed or
    screenshot briefing could not tell UAV 1's route from UAV 9's. Each route now carries a
    permanent label ``UAV <id>`` where its search pattern starts (in its own layer: hidden
    with the route)."""
    exe = _chromium()
    (page,) = export_plan(small_plan, "html", out_dir=tmp_path)
    dom = _run_chromium(exe, page, "--dump-dom")
    assert dom.returncode == 0, dom.stderr[-2000:]
    labels = re.findall(r'class="leaflet-tooltip[^"]*uav-label[^"]*"[^>]*><span>([^<]*)</span>',
                        dom.stdout)  # fmt: skip
    plan = load_plan(small_plan)
    want = sorted(f"UAV {u['id']}" for u in plan["uavs"] if len(u["waypoints_m"]) > 1)
    assert sorted(labels) == want and want
