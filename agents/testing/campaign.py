"""The hostile-input campaign: property-based cases over every external input.

    poc-env bench campaign [--cases 5000] [--seed 0] [--targets overrides,maps,...]

Each *target* is an input a user or a file can hand poc-env -- scenario overrides, prior maps
(arrays and files), region files, ``plan.json`` for export, command lines, environment
actions, GIS layers for ``scenario import``, the ``episodes.csv`` of ``summarise`` and the
data files of drift and terrain (velocity fields, particle files, DEMs, ``replan`` tracks:
:mod:`poc_env.agents.testing.campaign_files`) -- with
a hypothesis strategy that draws plausible values, typos and hostile values alike (strings
for numbers, bools, NaN, infinities, 1e308, 10**400, nulls, wrong shapes, random bytes). Every
case is run and classified:

* ``ok``: a valid result, checked for what would make it silently wrong (finite numbers,
  probabilities in [0, 1], a map summing to 1, probability mass conserved by a step, mission
  files that are strict JSON with coordinates on the globe, outputs only where asked);
* ``error``: a project error (:class:`poc_env.errors.PocEnvError`, exit status 2 on the command
  line) whose message names what is allowed;
* ``unclear``: a project error without ``allowed:`` or a field;
* ``traceback``: any other exception;
* ``silent``: a result that fails its check -- a silent wrong answer;
* ``hang``: a case still running after ``--case-timeout`` seconds (default 60), stopped by a
  ``SIGALRM`` in the campaign's own thread (no watcher thread or process) and recorded.

After each target the campaign counts its *orphans*: processes it started (its descendants, and
any process carrying its ``POC_ENV_CAMPAIGN_TAG`` environment marker, which catches children
re-parented to init) still alive. Unclear, traceback, silent, hang and orphan must be 0.
``tests/test_campaign.py`` runs every target through hypothesis in the default suite (1,280
cases, asserting no hang and no orphan); this command runs a large campaign and prints the
counts, the figure quoted in issue 27's closing note (``docs/inputs.md``). Needs ``hypothesis``
(the ``dev`` extra).
"""

from __future__ import annotations

import argparse
import contextlib
import copy
import importlib
import io
import json
import math
import os
import re
import signal
import stat
import sys
import tempfile
import threading
import traceback
import uuid
import warnings
from collections import Counter
from collections.abc import Callable
from html.parser import HTMLParser
from pathlib import Path
from typing import Any

import numpy as np

from poc_env.agents.testing.hostile import SilentWrong, check, hostile_scalars
from poc_env.errors import PocEnvError

OUTCOMES = ("ok", "error", "unclear", "traceback", "silent", "hang")
#: Outcomes that fail a campaign (with orphan processes, counted apart from the cases).
BAD = ("unclear", "traceback", "silent", "hang")
#: Seconds one case may run before it counts as a ``hang`` (``--case-timeout``).
CASE_TIMEOUT_S = 60.0
#: Environment variable that marks every process a campaign starts (see :func:`orphans`).
TAG_VAR = "POC_ENV_CAMPAIGN_TAG"
#: Most cases of one campaign (``--cases``): about a day on one core.
MAX_CASES = 1_000_000


class CaseTimeout(BaseException):
    """Raised in a case that ran past its time limit (a BaseException: ``except Exception`` in
    the code under test must not swallow it)."""


@contextlib.contextmanager
def time_limit(seconds: float | None):
    """Raise :class:`CaseTimeout` in this thread after ``seconds`` (``SIGALRM``; no thread or
    process is started). A no-op without a limit, off the main thread or without SIGALRM."""
    usable = (
        seconds is not None
        and seconds > 0
        and hasattr(signal, "setitimer")
        and threading.current_thread() is threading.main_thread()
    )
    if not usable:
        yield
        return

    def expire(signum: int, frame: Any) -> None:
        raise CaseTimeout(f"case still running after {seconds:g} s")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, float(seconds))  # type: ignore[arg-type]
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)


def classify(
    fn: Callable[[Any], None], case: Any, timeout_s: float | None = None
) -> tuple[str, str]:
    """Run ``fn(case)`` and return (outcome, detail); past ``timeout_s`` seconds it is a hang."""
    try:
        with warnings.catch_warnings(), time_limit(timeout_s):
            warnings.simplefilter("ignore")
            fn(case)
    except CaseTimeout as err:
        return "hang", str(err)
    except SilentWrong as err:
        return "silent", str(err)
    except PocEnvError as err:
        text = str(err)
        return ("error" if "allowed" in text else "unclear"), text
    except Exception:
        return "traceback", traceback.format_exc(limit=-3)
    return "ok", ""


# --------------------------------------------------------------------------- hostile values


def _near(default: Any):
    """Values around a field's default (mostly valid) or hostile ones."""
    from hypothesis import strategies as st

    if isinstance(default, bool):
        return st.one_of(st.booleans(), hostile_scalars())
    if isinstance(default, int):
        return st.one_of(st.integers(max(0, default - 3), default + 3), hostile_scalars())
    if isinstance(default, float):
        lo, hi = (0.2 * default, 3 * default) if default > 0 else (0.0, 1.0)
        return st.one_of(st.floats(lo, hi), hostile_scalars())
    return hostile_scalars()


# --------------------------------------------------------------------------- target: overrides


def scenario_leaves() -> dict[str, Any]:
    """Dotted YAML keys of ``small``'s scalar fields with their values (the override space)."""
    from poc_env.config import load_scenario

    out: dict[str, Any] = {}

    def walk(d: Any, prefix: str) -> None:
        for k, v in d.items():
            key = f"{prefix}{k}"
            if isinstance(v, dict):
                walk(v, key + ".")
            elif not isinstance(v, list):
                out[key] = v

    walk(load_scenario("small").to_dict(), "")
    out.pop("name", None)
    return out


def overrides_strategy():
    from hypothesis import strategies as st

    leaves = scenario_leaves()
    pairs = st.sampled_from(sorted(leaves)).flatmap(
        lambda k: st.tuples(st.just(k), _near(leaves[k]))
    )
    listy = st.sampled_from(
        [
            ("fleet", [{"takeoff": "A", "count": 2.0}]),
            ("fleet", [{"takeoff": "nowhere"}]),
            ("fleet", [{"takeoff": "A", "count": 65}]),
            ("airfields", [{"name": "A", "position_km": [float("nan"), 0]}]),
            ("airfields", [{"name": "A", "position_km": [1e308, 0]}]),
            ("map.prior.components", [{"mean_km": [10, 10], "sigma_km": [5, 5], "weight": 1e308}]),
            ("map.prior.components", [{"mean_km": [10, 10], "sigma_km": [0, 5]}]),
            ("map.prior.components", [{"mean_km": "here", "sigma_km": [5, 5]}]),
            ("map.no_fly_zones_km", [[[0, 0], [10, 10], [10, 0], [0, 10]]]),
            ("map.no_fly_zones_km", [[[0, 0], [1, 1]]]),
            ("map.threat_peaks", [{"center_km": [5, 5], "lambda_per_km2": -1}]),
            ("map.prior", None),
            ("uav", "fast"),
        ]
    )
    return st.lists(st.one_of(pairs, listy, table_names()), min_size=1, max_size=4).map(dict)


def _named_fields() -> dict[str, tuple[str, ...]]:
    """Scenario keys whose value names an entry of a table, with the table's names."""
    from poc_env._kernels.sensing import LAW_CODES
    from poc_env.theory.motion import LEEWAY_CLASSES, MODELS

    return {
        "target.model": tuple(MODELS),
        "target.leeway_class": tuple(LEEWAY_CLASSES),
        "sensor.law": tuple(LAW_CODES),
    }


def table_names():
    """(key, value) for the keys that name a table entry (target model, leeway class,
    detection law): a name of the table or a near miss of one (case, spaces, a letter off,
    another table's name), alone or beside the model that would use it."""
    from hypothesis import strategies as st

    fields = _named_fields()
    every = sorted({n for names in fields.values() for n in names})

    def near(name: str):
        misses = [name.upper(), f" {name}", f"{name} ", name[:-1], name + "s"]
        return st.sampled_from([name, *misses, name.replace("_", "-")])

    return st.sampled_from(sorted(fields)).flatmap(
        lambda k: st.tuples(
            st.just(k), st.one_of(st.sampled_from(fields[k]).flatmap(near), st.sampled_from(every))
        )
    )


def run_overrides(overrides: dict[str, Any]) -> None:
    """A scenario from hostile overrides; if it loads, three steps of the env must be sane."""
    import poc_env
    from poc_env.config import load_scenario

    sc = load_scenario("small", {**overrides, "episode.horizon_steps": 3})
    named = sc.to_dict()
    for key, names in _named_fields().items():  # a loaded scenario names only table entries
        section, name = key.split(".")
        value = named[section][name]
        check(value in names, f"{key} {value!r} loaded but is not one of {names}")
    env = poc_env.parallel_env(sc, obs_type="flat")
    obs, _ = env.reset(seed=0)
    rng = np.random.default_rng(0)
    for _ in range(3):
        if not env.agents:
            break
        actions = {a: rng.uniform(-1, 1, 3).astype(np.float32) for a in env.agents}
        obs, rew, *_ = env.step(actions)
        check(all(np.all(np.isfinite(o)) for o in obs.values()), "observation not finite")
        check(all(math.isfinite(r) for r in rew.values()), "reward not finite")
        st = env.sim_state
        check(bool(0.0 <= st.posc[0] <= 1.0 + 1e-9), f"POSC {st.posc[0]} outside [0, 1]")
        mass = float(st.posc[0] + st.belief[0].sum())
        check(abs(mass - float(st.initial_mass[0])) < 1e-9, f"mass not conserved: {mass!r}")


# --------------------------------------------------------------------------- target: maps


def maps_strategy():
    from hypothesis import strategies as st
    from hypothesis.extra import numpy as hnp

    shapes = st.sampled_from([(8, 8), (8, 8), (8, 8), (8, 7), (7, 8), (64,), (0, 8), (8, 8, 1)])
    elems = st.one_of(
        st.floats(0, 1),
        st.floats(allow_nan=True, allow_infinity=True),
        st.sampled_from([0.0, 1e308, 5e-324, -0.0, -1e-12, 1e-300]),
    )
    arrays = shapes.flatmap(lambda s: hnp.arrays(np.float64, s, elements=elems))
    complex_ = st.just(np.ones((8, 8), complex))
    objects = st.sampled_from([[["a"] * 8] * 8, None, "map", [[1, 2], [3]]])
    files = st.tuples(
        st.sampled_from([".npy", ".csv", ".txt", ""]),
        st.one_of(st.binary(max_size=200), st.sampled_from([b"\x93NUMPY", b"0,1\n1,0\n"])),
    )
    return st.one_of(arrays, arrays, complex_, objects, files)


def run_maps(case: Any) -> None:
    """A prior from an array or a file's bytes; if accepted it is a finite map summing to 1."""
    from poc_env.config import load_scenario
    from poc_env.theory.probability_map import Grid, load_map, validate_map

    grid = Grid.from_config(load_scenario("small").map)
    if isinstance(case, tuple):
        suffix, data = case
        with tempfile.TemporaryDirectory() as d:
            path = Path(d) / f"map{suffix}"
            path.write_bytes(data)
            m = load_map(path, grid)
    else:
        m = validate_map(case, grid)
    check(m.shape == grid.shape, f"shape {m.shape}")
    check(bool(np.all(np.isfinite(m)) and np.all(m >= 0)), "map values not finite >= 0")
    check(abs(float(m.sum()) - 1.0) < 1e-9, f"map sums to {m.sum()!r}")


# --------------------------------------------------------------------------- target: regions

_REGION = {
    "id": 1,
    "kind": "polygon",
    "airfield": "A",
    "spacing_km": 12,
    "direction_deg": 30,
    "vertices_km": [[0, 0], [100, 0], [100, 80], [0, 80]],
}
_CIRCLE = {
    "id": 2,
    "kind": "circle",
    "airfield": "B",
    "pattern": "expanding_square",
    "spacing_km": 8,
    "center_km": [200, 150],
    "radius_km": 40,
    "second_search": False,
}


def regions_strategy():
    from hypothesis import strategies as st

    keys = sorted(set(_REGION) | set(_CIRCLE) | {"holes_km", "landing"})
    values = st.one_of(
        hostile_scalars(),
        st.sampled_from(
            [
                [[0, 0], [100, 100], [100, 0], [0, 100]],
                [[[10, 10], [20, 10]]],
                [[[10, 10], [20, 10], [20, 20]]],
                [[0, 0], [1, 1], [2, 2]],
                "sector",
                "spiral",
                "parallel",
                "circle",
                "polygon",
                "A",
                "Z",
            ]
        ),
    )
    change = st.dictionaries(st.sampled_from(keys), values, max_size=3)
    return st.tuples(st.sampled_from([_REGION, _CIRCLE]), change)


def run_regions(case: tuple[dict, dict]) -> None:
    """A region file with hostile fields; if it loads, its survey must be finite."""
    import yaml

    from poc_env.agents.planning.survey import load_regions, run_survey

    base, change = case
    region = {**base, **change}
    doc = {"name": "fuzz", "scenario": "paper_6_1", "regions": [region]}
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "regions.yaml"
        path.write_text(yaml.safe_dump(doc))
        plan = load_regions(path)
        res = run_survey("paper_6_1", plan)
    for r in res.rows:
        nums = (r.track_length_km, r.pod, r.poc, r.pos, r.flight_time_h)
        check(all(math.isfinite(v) for v in nums), f"survey row not finite: {r}")
        check(0 <= r.pod <= 1 and 0 <= r.pos <= 1 + 1e-9, f"probabilities out of range: {r}")
    for t in res.tracks:
        check(bool(np.all(np.isfinite(t))), "track not finite")


# --------------------------------------------------------------------------- target: plan.json


def sample_plan() -> dict[str, Any]:
    """A valid schema-1 plan of two UAVs."""
    uavs = []
    for k in range(2):
        uavs.append(
            {
                "id": k + 1,
                "rectangle": {
                    "center_m": [50e3, 60e3], "length_m": 40e3, "width_m": 20e3,
                    "theta_deg": 30.0,
                },
                "spacing_m": 5e3, "takeoff_m": [20e3, -60e3], "landing_m": [20e3, -60e3],
                "waypoints_m": [[10e3, 10e3], [60e3, 10e3], [60e3, 20e3]],
                "track_length_m": 300e3, "flight_time_s": 9000.0, "pod": 0.79, "poc": 0.2,
                "pos": 0.158, "feasible": True,
            }
        )  # fmt: skip
    return {
        "schema": 1, "scenario": "paper_6_2", "seed": 1, "map_source": "builtin",
        "optimizer": {"name": "adaptive_de", "settings": {}}, "runtime_s": 0.4,
        "posc": 0.3, "upper_bound": 0.5, "uavs": uavs,
    }  # fmt: skip


_PLAN_PATHS = [
    ("schema",), ("posc",), ("upper_bound",), ("seed",), ("uavs",), ("optimizer",),
    ("uavs", 0, "id"), ("uavs", 0, "waypoints_m"), ("uavs", 0, "waypoints_m", 0),
    ("uavs", 0, "waypoints_m", 0, 0), ("uavs", 0, "takeoff_m"), ("uavs", 0, "landing_m", 1),
    ("uavs", 0, "rectangle"), ("uavs", 0, "rectangle", "theta_deg"),
    ("uavs", 0, "rectangle", "center_m"), ("uavs", 1, "pos"), ("uavs", 1, "flight_time_s"),
    ("uavs", 1, "spacing_m"), ("uavs", 1, "feasible"), ("uavs", 1, "id"),
]  # fmt: skip


def plans_strategy():
    from hypothesis import strategies as st

    values = st.one_of(
        hostile_scalars(),
        st.sampled_from(
            ["../../escaped", "a/b", "UAV 1", "x" * 65, [1e300, 1e300], [float("nan"), 0], [1],
             [[0, 0]], {"center_m": None}]
        ),
    )  # fmt: skip
    edits = st.lists(st.tuples(st.sampled_from(_PLAN_PATHS), values), max_size=3)
    from poc_env.agents.mission.formats import FORMATS

    fmt = st.sampled_from(list(FORMATS))  # every registered format
    origin = st.one_of(
        st.sampled_from(["45.5,126.6", "-45,7", "91,0", "nan,0", "0,181", "x", "89.95,0"]),
        st.tuples(st.floats(-89, 89), st.floats(-180, 180)).map(lambda t: f"{t[0]},{t[1]}"),
    )
    return st.tuples(edits, fmt, origin, st.booleans())


def _set_path(doc: Any, path: tuple, value: Any) -> None:
    """Set ``doc[path]`` to a copy of ``value``: a strategy's values are shared objects (the
    same list in two edits, or across cases), and a later edit into one must not make the
    document circular or change the strategy's constants."""
    node = doc
    for k in path[:-1]:
        node = node[k]
    node[path[-1]] = copy.deepcopy(value)


def run_plans(case: tuple[list, str, str, bool]) -> None:
    """Export a mutated plan.json; if it exports, the files must be safe to fly."""
    from poc_env.agents.mission.export import export_plan

    edits, fmt, origin, raw_nan = case
    plan = sample_plan()
    for path, value in edits:
        with contextlib.suppress(LookupError, TypeError):
            _set_path(plan, path, value)
    with tempfile.TemporaryDirectory() as d:
        root = Path(d)
        out = root / "out"
        src = root / "plan.json"
        try:
            text = json.dumps(plan, allow_nan=raw_nan)
        except ValueError:
            text = json.dumps(plan, allow_nan=True)
        src.write_text(text)
        files = export_plan(src, fmt, origin, out)
        written = {p for p in root.rglob("*") if p.is_file()} - {src}
        check(all(out in p.parents for p in written), f"file outside --out: {written}")
        for f in files:
            check_output_file(f)


def check_output_file(f: Path) -> None:
    """An exported file is well formed and its coordinates are finite and on the globe; each
    file kind an export format writes (:data:`OUTPUT_CHECKS`, by suffix) has its check."""
    suffix = f.suffix.lower()
    if suffix not in OUTPUT_CHECKS:
        raise SilentWrong(f"no check for an exported {suffix} file ({f.name}): add one")
    OUTPUT_CHECKS[suffix](f)


def _check_png(f: Path) -> None:
    check(f.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", f"not a PNG: {f.name}")


def _check_json_file(f: Path) -> None:
    """Strict JSON, coordinates on the globe; GeoJSON exterior rings closed and
    counter-clockwise (RFC 7946); a QGC .plan valid by its JSON Schema."""
    data = json.loads(f.read_text(encoding="utf-8"), parse_constant=_refuse_constant)
    fmt = "geojson" if f.suffix == ".geojson" else "qgc"
    _check_coordinates(data, fmt)
    if fmt == "geojson":
        from poc_env.agents.mission.formats.geojson import ring_area

        for feat in data["features"]:
            if feat["geometry"]["type"] == "Polygon":
                ring = feat["geometry"]["coordinates"][0]
                check(ring[0] == ring[-1], "GeoJSON ring not closed")
                check(ring_area(ring) >= 0, "GeoJSON exterior ring clockwise (RFC 7946)")
    else:
        from poc_env.agents.mission.formats.qgc import validate_qgc

        errs = validate_qgc(data)
        check(not errs, f"QGC .plan not valid by its schema: {errs[:2]}")


def _check_kml(f: Path) -> None:
    """Valid by the OGC KML 2.2 XSD (lxml), and no nan/inf coordinates."""
    from poc_env.agents.mission.formats.kml import validate_kml

    errs = validate_kml(f)
    check(not errs, f"KML not valid by ogckml22.xsd: {errs[:2]}")
    low = f.read_text(encoding="utf-8").lower()
    check("nan," not in low and "inf," not in low, "KML with nan/inf")


#: The markup the text target injects into plan strings and file names: an exported HTML page
#: must never contain it as an element (escaped in text, ``\\u003c`` in the script's JSON).
INJECTED_TAG = "x-injected"


class _Tags(HTMLParser):
    """The start tags of a page (html.parser: script contents are not parsed as markup)."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.tags: list[str] = []

    def handle_starttag(self, tag: str, attrs: Any) -> None:
        self.tags.append(tag)


def _check_html(f: Path) -> None:
    """The map report: parsed by html.parser with no injected element and the page's own
    structure intact; its plan data is strict JSON and every drawn point is on the globe."""
    body = f.read_text(encoding="utf-8")
    parser = _Tags()
    parser.feed(body)
    parser.close()
    check(INJECTED_TAG not in parser.tags, "injected markup became an HTML element")
    check(parser.tags.count("script") == 3, f"HTML scripts: {parser.tags.count('script')} != 3")
    check(parser.tags.count("table") == 1, "HTML report without its one table")
    m = re.search(r'<script type="application/json" id="plan-data">(.*?)</script>', body, re.S)
    check(m is not None, "HTML report without its plan data")
    assert m is not None
    data = json.loads(m.group(1), parse_constant=_refuse_constant)
    pairs = []
    for u in data["uavs"]:
        for line in [
            *u["transit"],
            u["search"],
            *u["approach"],
            *(r["latlon"] for r in u["rings"]),
        ]:
            pairs += [tuple(p) for p in line]
    pairs += [tuple(a["latlon"]) for a in data["airfields"]]
    for lat, lon in pairs:
        check(math.isfinite(lat) and math.isfinite(lon), "coordinate not finite")
        check(-90 <= lat <= 90 and -180 <= lon <= 180, f"coordinate off the globe: {lat}, {lon}")


#: suffix of an exported file -> its check (:func:`check_output_file`)
OUTPUT_CHECKS = {
    ".png": _check_png,
    ".geojson": _check_json_file,
    ".plan": _check_json_file,
    ".kml": _check_kml,
    ".html": _check_html,
}


def _refuse_constant(name: str) -> float:
    raise SilentWrong(f"not strict JSON: {name}")


def _positions(coords: Any) -> list[list[float]]:
    """The positions of a GeoJSON ``coordinates`` member, however deeply its parts nest."""
    if coords and isinstance(coords[0], (int, float)):
        return [[float(v) for v in coords]]
    return [p for part in coords for p in _positions(part)]


def _check_coordinates(data: Any, fmt: str) -> None:
    pairs: list[tuple[float, float]] = []
    if fmt == "geojson":
        for feat in data["features"]:  # Multi* parts (cut at the antimeridian) nest deeper
            pairs += [(p[1], p[0]) for p in _positions(feat["geometry"]["coordinates"])]
    else:
        for item in data["mission"]["items"]:
            if item.get("params") and item["params"][4] is not None:
                pairs.append((item["params"][4], item["params"][5]))
    for lat, lon in pairs:
        check(math.isfinite(lat) and math.isfinite(lon), "coordinate not finite")
        check(-90 <= lat <= 90 and -180 <= lon <= 180, f"coordinate off the globe: {lat}, {lon}")


# --------------------------------------------------------------------------- target: text

#: Hostile text for every string field of plan.json and for file names: newlines (YAML/CSV
#: line injection), markup and entities (XML/HTML injection), quotes, C0 controls and lone
#: surrogates (not encodable in XML 1.0 / UTF-8), bidi and line-separator characters.
HOSTILE_TEXT = [
    "line\nbreak: injected\nkey: 1",
    "cr\r\nlf",
    f"<{INJECTED_TAG} onload=alert(1)>x</{INJECTED_TAG}>",
    f"</script><{INJECTED_TAG}>",
    "]]>&amp;&lt;'\"",
    "<!-- c --><![CDATA[x]]>",
    "tab\there",
    "\u2028\u2029\x85\u202e rtl",
    "\x00nul",
    "bell\x07",
    "esc\x1b[31m",
    "\ud800 lone",
    "lone \udfff",
    "\ufffe",
    "x" * 70,
    "ünïcödé 漢字 🚁",
]

#: The string fields of plan.json the text target writes hostile text into.
_TEXT_PATHS = [
    ("scenario",), ("map_source",), ("optimizer", "name"), ("optimizer", "settings", "note"),
    ("rectangle_rule",), ("airfields", 0, "name"), ("uavs", 0, "id"), ("uavs", 1, "note"),
]  # fmt: skip
#: File names (plan stems) the text target exports under.
_TEXT_STEMS = ["plan", "a\nb", f"<{INJECTED_TAG}>", "q'\"&", "sp ace", "ünï"]


def text_strategy():
    from hypothesis import strategies as st

    from poc_env.agents.mission.formats import FORMATS

    text = st.one_of(st.sampled_from(HOSTILE_TEXT), st.text(max_size=12))
    edits = st.lists(st.tuples(st.sampled_from(_TEXT_PATHS), text), min_size=1, max_size=3)
    return st.tuples(edits, st.sampled_from(list(FORMATS)), st.sampled_from(_TEXT_STEMS))


def run_text(case: tuple[list, str, str]) -> None:
    """Export a plan whose strings (and file name) are hostile: refused by name, or every
    output is valid by its format's validator with the text escaped (:data:`OUTPUT_CHECKS`)."""
    from poc_env.agents.mission.export import export_plan

    edits, fmt, stem = case
    plan = sample_plan()
    plan["airfields"] = [{"name": "A", "position_m": [20e3, -60e3]}]
    plan["rectangle_rule"] = "lines along theta"
    for path, value in edits:
        with contextlib.suppress(LookupError, TypeError):
            _set_path(plan, path, value)
    with tempfile.TemporaryDirectory() as d:
        root = Path(d)
        src = root / f"{stem}.json"
        src.write_text(json.dumps(plan), encoding="utf-8")  # ASCII: \u escapes
        files = export_plan(src, fmt, "45.75,126.65", root / "out")
        for f in files:
            check_output_file(f)


# --------------------------------------------------------------------------- target: episodes


def _episodes_header() -> list[str]:
    from poc_env.agents.experiments.evaluate import EPISODE_COLUMNS

    return [*EPISODE_COLUMNS, "time_to_detection_s", "steps", "random_prior"]


def sample_episodes() -> list[list[Any]]:
    """Rows of a valid episodes.csv (``evaluate --out``): two policies on the same 3 seeds."""
    rows = []
    for k, policy in enumerate(("lawnmower", "random")):
        for s in range(3):
            posc = 0.4 - 0.3 * k + 0.01 * s
            rows.append([policy, 1000 + s, posc, 0.9, 0.85, posc / 0.85, s % 2 == 0, 2 * s, 0, 3,
                         600.0 + 60 * s if s % 2 == 0 else "", 40 + s, False])  # fmt: skip
    return rows


def episodes_strategy():
    """An episodes.csv as ``poc-env summarise`` reads it: a valid file with hostile cells
    (numbers out of range, NaN, text, empty), a column dropped or renamed, rows cut short or
    swapped between policies, or raw bytes."""
    from hypothesis import strategies as st

    width = len(_episodes_header())
    cell = st.tuples(st.integers(0, 5), st.integers(0, width - 1), hostile_scalars())
    return st.one_of(
        st.tuples(st.just("cells"), st.lists(cell, max_size=4)),
        st.tuples(st.just("drop"), st.integers(0, width - 1)),
        st.tuples(st.just("short"), st.integers(0, 5)),
        st.tuples(st.just("seed"), st.integers(0, 5)),
        st.tuples(st.just("bytes"), st.binary(max_size=200)),
    )


def run_episodes(case: tuple[str, Any]) -> None:
    """``summarise`` of a hostile episodes.csv: if it reads, the summary is finite and its
    means and intervals are those of the file's POSC values."""
    import csv as csv_mod

    from poc_env.agents.experiments.evaluate import read_episodes
    from poc_env.stats import ci95

    kind, what = case
    header, rows = _episodes_header(), sample_episodes()
    if kind == "cells":
        for r, c, value in what:
            rows[r][c] = value
    elif kind == "drop":
        header = header[:what] + header[what + 1 :]
        rows = [row[:what] + row[what + 1 :] for row in rows]
    elif kind == "short":
        rows[what] = rows[what][:-3]
    elif kind == "seed":
        rows[what][1] = 999  # a policy with another seed than the first policy's
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "episodes.csv"
        if kind == "bytes":
            path.write_bytes(what)
        else:
            with path.open("w", newline="", encoding="utf-8", errors="surrogatepass") as f:
                w = csv_mod.writer(f)
                w.writerow(header)
                w.writerows(rows)
        ev = read_episodes(path)
        files = ev.summary_files([ev.policies[0]])
    for row in ev.rows():
        posc = [e.posc for e in ev.episodes if e.policy == row["policy"]]
        check(math.isfinite(row["posc_mean"]) and 0 <= row["posc_mean"] <= 1, f"mean {row}")
        check(abs(row["posc_ci95"] - ci95(posc)) <= 1e-12, f"interval {row}")
        check(math.isfinite(row["posc_ci95"]), f"interval not finite: {row}")
    check(all(math.isfinite(float(x)) for x in (ev.bound, ev.bound_reach or 0.0)), "bounds")
    check(set(files) == {"evaluate.csv", "evaluate.txt", "paired.csv"}, f"files {set(files)}")


# --------------------------------------------------------------------------- target: utm


def utm_strategy():
    from hypothesis import strategies as st

    lat = st.one_of(st.floats(-80, 84), st.sampled_from([0.0, -0.0, 45.75, -33.9, 83.9]))
    lon = st.one_of(st.floats(-180, 180), st.sampled_from([-180.0, 180.0, 179.99, -179.99, 0.0]))
    zone = st.one_of(st.integers(1, 60), st.sampled_from([0, 61, -1, True, 2.5, None, "52"]))
    return st.tuples(lat, lon, zone)


def run_utm(case: tuple[float, float, Any]) -> None:
    """A UTM zone across the globe from the origin: refused by name, or the map's distances
    near the origin agree with the ellipsoid's to 2 % (a zone 9 degrees off: 1.2 %)."""
    from pyproj import Geod

    from poc_env.agents.mission.crs import make_crs, to_geographic

    lat, lon, zone = case
    crs = make_crs("utm", (lat, lon), zone=zone)
    (a, b), (c, e) = to_geographic([(0.0, 0.0), (10e3, 0.0)], crs)
    dist = Geod(ellps="WGS84").inv(b, a, e, c)[2]
    check(abs(dist / 10e3 - 1.0) < 0.02, f"UTM zone {zone}: 10 km of map is {dist:.0f} m")


# --------------------------------------------------------------------------- target: cli


# "SPECIAL" stands for a path that is not a regular file (a FIFO in the case's own folder):
# never the machine's /dev/null, which an output path's atomic rename would replace (as root:
# for everyone; a fresh-clone CI run did, before check_replaceable)
_CLI_VALUES = ["-1", "0", "1", "1.5", "inf", "nan", "", "abc", "10**400", "1e308",
               "999999999999999999999", "SPECIAL", ".", "-45,7", "x/../../y"]  # fmt: skip
#: Options whose value scales a command's work (episodes, generations, steps, frames).
CLI_WORK_OPTIONS = frozenset(
    ["--popsize", "--maxiter", "--episodes", "--max-steps", "--total-timesteps", "--n-steps",
     "--uavs", "--workers", "--n-envs"]
)  # fmt: skip
#: Largest integer drawn for a work option (a case stays seconds, far below --case-timeout).
MAX_CLI_WORK = 64


def cli_strategy():
    from hypothesis import strategies as st

    values = st.one_of(
        st.sampled_from(_CLI_VALUES),
        st.integers(-5, 5000).map(str),  # larger ones: the sampled 1e308, 10**21
    )
    commands = st.sampled_from(
        [
            ["plan", "--scenario", "small", "--maxiter", "1", "--popsize", "4", "--quiet"],
            ["evaluate", "--scenario", "small", "--episodes", "1", "--policies", "lawnmower",
             "--quiet"],
            ["survey", "--scenario", "paper_6_1", "--regions", "paper_6_1_polygons"],
            ["render", "--scenario", "small", "--max-steps", "2"],
            ["export", "PLAN", "--format", "geojson", "--origin", "45,126"],
            ["scenarios"],
            ["train", "--scenario", "small", "--total-timesteps", "64", "--n-envs", "1",
             "--n-steps", "32", "--batch-size", "32", "--no-progress"],
        ]
    )  # fmt: skip
    options = st.sampled_from(
        ["--seed", "--uavs", "--popsize", "--maxiter", "--episodes", "--workers", "--out",
         "--plot", "--origin", "--format", "--map", "--scenario", "--policies", "--every",
         "--max-memory-gb", "--regions", "--max-steps", "--learning-rate", "--gamma",
         "--n-envs", "--total-timesteps", "--n-steps", "--ent-coef", "--run-dir"]
    )  # fmt: skip
    # A valid work size in the thousands is honest work, not a hang (seed 63: `evaluate
    # --episodes 1708` ran past the 60 s limit): these options draw small integers, and the
    # sampled 1e308, 10**400 and 10**21 still test their range checks.
    small = st.one_of(st.sampled_from(_CLI_VALUES), st.integers(-5, MAX_CLI_WORK).map(str))
    pair = options.flatmap(
        lambda o: st.tuples(st.just(o), small if o in CLI_WORK_OPTIONS else values)
    )
    return st.tuples(commands, st.lists(pair, max_size=2))


def run_cli(case: tuple[list[str], list[tuple[str, str]]]) -> None:
    """A command line with hostile option values: exit 0, or 2 with ``error: ...``; every file
    written inside the working folder."""
    from poc_env.cli import main

    base, opts = case
    with tempfile.TemporaryDirectory() as d:
        root = Path(d)
        plan = root / "plan.json"
        plan.write_text(json.dumps(sample_plan()))
        argv = [str(plan) if b == "PLAN" else b for b in base]
        special = root / "special"
        os.mkfifo(special)  # not a regular file: must be refused as an output, never replaced
        for opt, val in opts:
            val = val.replace("x/../../y", str(root / "x" / ".." / "y"))
            argv += [opt, str(special) if val == "SPECIAL" else val]
        if base[0] == "train" and "--run-dir" not in argv:
            argv += ["--run-dir", str(root / "run")]
        if "--out" not in argv and base[0] in ("plan", "render", "survey", "evaluate"):
            argv += ["--out", str(root / ("o.json" if base[0] == "plan" else "o.gif"
                                          if base[0] == "render" else "o"))]  # fmt: skip
        out, err = io.StringIO(), io.StringIO()
        cwd = os.getcwd()
        os.chdir(root)
        try:
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                try:
                    code = main(argv)
                except SystemExit as exc:  # argparse: usage errors exit 2
                    code = int(exc.code or 0)
        finally:
            os.chdir(cwd)
        if not stat.S_ISFIFO(os.lstat(special).st_mode):
            raise SilentWrong(f"the FIFO given as a path was replaced by {argv}")
        if not stat.S_ISCHR(os.stat("/dev/null").st_mode):
            raise SilentWrong(f"/dev/null is no longer a device after {argv}")
        if code not in (0, 2):
            raise SilentWrong(f"exit status {code} for {argv}")
        if code == 2:
            msg = err.getvalue()
            if "Traceback" in msg:
                raise RuntimeError(msg)
            if not msg.strip():
                raise SilentWrong(f"exit 2 without a message for {argv}")
            if msg.startswith("error:") and "allowed" not in msg and "usage:" not in msg:
                raise PocEnvError(msg)  # counted as unclear
            raise _CliError(msg)


class _CliError(PocEnvError):
    """A clean exit 2 (counted as a clear error)."""

    def __str__(self) -> str:
        return "allowed: " + super().__str__()


# --------------------------------------------------------------------------- target: actions


def actions_strategy():
    from hypothesis import strategies as st
    from hypothesis.extra import numpy as hnp

    good = hnp.arrays(np.float32, 3, elements=st.floats(-1, 1, width=32))
    bad = st.one_of(
        hnp.arrays(np.float64, st.sampled_from([(3,), (2,), (4,), (3, 1)]),
                   elements=st.floats(allow_nan=True, allow_infinity=True)),
        st.sampled_from([None, "up", [1, 2, 3], ["1", "2", "3"], [1, [2], 3], 1.0, True,
                         np.array([1 + 1j, 0, 0]), {"x": 1}]),
    )  # fmt: skip
    per_agent = st.one_of(good, good, bad)
    return st.tuples(
        st.lists(per_agent, min_size=3, max_size=3),
        st.sampled_from(["all", "missing", "extra", "list", "none"]),
    )


def run_actions(case: tuple[list, str]) -> None:
    """``step()`` with hostile actions: a ConfigError or a sane step."""
    import poc_env

    acts, shape = case
    env = poc_env.parallel_env("small", obs_type="flat", episode__horizon_steps=5)
    env.reset(seed=1)
    actions: Any = dict(zip(env.agents, acts))
    if shape == "missing":
        actions.pop(env.agents[0])
    elif shape == "extra":
        actions["uav_99"] = acts[0]
    elif shape == "list":
        actions = list(acts)
    elif shape == "none":
        actions = None
    obs, rew, *_ = env.step(actions)
    check(all(np.all(np.isfinite(o)) for o in obs.values()), "observation not finite")
    check(all(math.isfinite(r) for r in rew.values()), "reward not finite")
    st = env.sim_state
    check(bool(np.all(np.isfinite(st.pos))), "position not finite")


# --------------------------------------------------------------------------- target: runtime
# Issue 27's runtime classes: Ray addresses where something that is not Ray listens (raw TCP,
# a bare HTTP/2 answer, gRPC servers that are not Ray's), run folders in every state a kill
# leaves (resumed, or their own command rerun), damaged or hostile TensorBoard logs for
# `poc-env curve`, oversized sizes, deeply nested JSON, options that override each other,
# heading actions outside their Box.

_SETTINGS = bytes([0, 0, 0, 4, 0, 0, 0, 0, 0])  # an HTTP/2 SETTINGS frame: any gRPC server's
_REPLIES = [None, b"", b"HTTP/1.1 400 Bad Request\r\n\r\n", b"\x00" * 9, b"SSH-2.0-x\r\n",
            _SETTINGS, _SETTINGS + b"\x00" * 64]  # fmt: skip
#: gRPC servers that are not Ray: no service of Ray's, a GCS answer without a cluster id, an
#: UNAUTHENTICATED refusal that is not Ray's.
_GRPC_FAKES = ["no_service", "no_cluster_id", "other_unauthenticated"]
_CURVE_DAMAGE = ["none", "truncated", "garbage", "empty", "flipped"]
_RESUME_STATES = ["empty", "config_only", "garbage_config", "nested_config", "nan_config",
                  "unknown_key", "rllib_with_checkpoint", "rllib_without_checkpoint"]  # fmt: skip
_TRAIN_SIZES = [("net_arch", [10**6, 10**6]), ("net_arch", [2**31]), ("n_steps", 10**6),
                ("batch_size", 10**7), ("n_steps", 1)]  # fmt: skip
_CONFLICTS = [
    ["train", "--task", "UAVSearch-Small-Heading-v1", "--scenario", "paper_6_1"],
    ["train", "--task", "UAVSearch-Small-Heading-v1", "--no-random-priors"],
    ["train", "--net-arch", "8"], ["train", "--engine", "rllib", "--n-envs", "2"],
    ["train", "--recipe", "central", "--approach-shaping", "1"],
    ["train", "--bc-epochs", "2"], ["train", "--rllib-policies", "per_uav"],
    ["evaluate", "--task", "UAVSearch-Small-Heading-v1", "--scenario", "small"],
    ["plan", "--scenario", "small", "--uavs", "2", "--overrides", "fleet=[{takeoff: A, count: 2}]"],
    ["plan", "--scenario", "small", "--planner", "allocation", "--optimizer", "cmaes"],
    ["plan", "--scenario", "small", "--planner", "allocation", "--popsize", "8"],
    ["render", "--scenario", "small", "--overrides", "episode.horizon_steps=10000000",
     "--max-steps", "10000000"],
]  # fmt: skip


def runtime_strategy():
    from hypothesis import strategies as st

    wild = st.one_of(st.floats(-1e308, 1e308), st.sampled_from([1.8e307, -5.0, 3.0, 1e-300]))
    return st.one_of(
        st.tuples(st.just("ray"), st.sampled_from(_REPLIES), st.booleans()),
        st.tuples(st.just("resume"), st.sampled_from(_RESUME_STATES)),
        st.tuples(st.just("rerun"), st.sampled_from(_RESUME_STATES), st.booleans()),
        st.tuples(st.just("grpc"), st.sampled_from(_GRPC_FAKES), st.booleans()),
        st.tuples(st.just("curve"), st.sampled_from(_CURVE_DAMAGE),
                  st.lists(st.tuples(st.integers(-(2**62), 2**62), wild), min_size=0, max_size=6),
                  st.one_of(st.none(), st.integers(-5, 2**62))),
        st.tuples(st.just("size"), st.sampled_from(_TRAIN_SIZES)),
        st.tuples(st.just("json"), st.integers(1, 3000), st.sampled_from(["[", "{\"a\":"]),
                  st.sampled_from(["1", "NaN", "Infinity", "-Infinity", "1e999", "\"x\""])),
        st.tuples(st.just("conflict"), st.sampled_from(_CONFLICTS)),
        st.tuples(st.just("heading"), st.lists(wild, min_size=6, max_size=6)),
    )  # fmt: skip


def run_runtime(case: tuple) -> None:
    """One of issue 27's runtime classes: a clear error (within seconds) or a sane result."""
    kind = case[0]
    if kind == "ray":
        _run_ray_address(case[1], case[2])
    elif kind == "resume":
        _run_resume_state(case[1])
    elif kind == "rerun":
        _run_resume_state(case[1], rerun=True, same=case[2])
    elif kind == "grpc":
        _run_grpc_fake(case[1], case[2])
    elif kind == "curve":
        _run_curve(*case[1:])
    elif kind == "size":
        from poc_env.agents.rl.args import TrainArgs
        from poc_env.agents.rl.train import check_sizes
        from poc_env.config import load_scenario

        field, value = case[1]
        args = TrainArgs(scenario="small", recipe="central", **{field: value})
        check_sizes(args, load_scenario("small"))  # must refuse each of these
        raise SilentWrong(f"{field}={value!r} passed the size checks")
    elif kind == "json":
        _run_nested_json(*case[1:])
    elif kind == "conflict":
        run_cli((case[1], []))
        raise SilentWrong(f"conflicting options accepted: {case[1]}")
    else:
        _run_heading(np.asarray(case[1], dtype=np.float64))


def _run_ray_address(reply: bytes | None, client: bool) -> None:
    import socket
    import threading
    import time

    from poc_env.agents.rl.cluster import probe

    srv = socket.create_server(("127.0.0.1", 0))
    conns = []

    def serve() -> None:
        with contextlib.suppress(OSError):
            conn, _ = srv.accept()
            conns.append(conn)
            if reply is not None:
                conn.sendall(reply)

    t = threading.Thread(target=serve, daemon=True)
    t.start()
    address = ("ray://" if client else "") + f"127.0.0.1:{srv.getsockname()[1]}"
    t0 = time.perf_counter()
    try:
        probe(address, timeout_s=0.5)
    finally:
        srv.close()
        t.join(2)
        for c in conns:
            c.close()
        check(time.perf_counter() - t0 < 5, "the probe took more than 5 s")
    raise SilentWrong(f"a service that is not Ray passed the probe ({reply!r})")


def _run_resume_state(state: str, rerun: bool = False, same: bool = True) -> None:
    """A run folder as a kill leaves it, continued with ``--resume`` or (``rerun``) by running
    a command again with ``--run-dir`` on it: its own (``same``) or one of other options. A
    model, or a clear error; never a run over another run's options."""
    from poc_env.agents.rl.args import TrainArgs
    from poc_env.agents.rl.train import train

    with tempfile.TemporaryDirectory() as d:
        run = Path(d) / "run"
        run.mkdir()
        small: dict[str, Any] = {
            "scenario": "small", "overrides": ["episode.horizon_steps=4"], "n_envs": 1,
            "n_steps": 4, "batch_size": 4, "n_epochs": 1, "total_timesteps": 12,
            "progress": False, "run_dir": str(run),
        }  # fmt: skip
        texts = {
            "config_only": json.dumps(small),
            "garbage_config": "{not json",
            "nested_config": "[" * 5000 + "]" * 5000,
            "nan_config": json.dumps({**small, "learning_rate": float("nan")}),
            "unknown_key": json.dumps({**small, "lr": 1}),
            "rllib_with_checkpoint": json.dumps({**small, "engine": "rllib"}),
            "rllib_without_checkpoint": json.dumps({**small, "engine": "rllib", "n_envs": 1}),
        }
        if state in texts:
            (run / "config.json").write_text(texts[state])
        if state == "rllib_with_checkpoint":
            (run / "checkpoint").mkdir()
        if state == "rllib_without_checkpoint":
            return  # trains on Ray: tests/rl/test_rllib.py covers it; not in a campaign
        before = (run / "config.json").read_bytes() if state in texts else None
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if not rerun:
                out = train(TrainArgs(resume=str(run), progress=False))
            else:
                try:
                    out = train(TrainArgs(**{**small, "seed": 0 if same else 1}))
                except PocEnvError:
                    now = (run / "config.json").read_bytes() if before is not None else None
                    check(now == before, f"a refused rerun changed a {state} run's config.json")
                    raise
                ok = state == "empty" or (state == "config_only" and same)
                check(ok, f"a rerun of {'its' if same else 'other'} options trained over a "
                      f"{state} run")  # fmt: skip
        check((out / "model.zip").is_file(), f"resume of a {state} run wrote no model")


def _run_grpc_fake(fake: str, client: bool) -> None:
    """A gRPC server on 127.0.0.1 that is not Ray (:data:`_GRPC_FAKES`): the probe refuses it."""
    from concurrent import futures

    try:
        import grpc

        # Ray's generated modules (untyped: their attributes are made at import)
        gcs_service_pb2 = importlib.import_module("ray.core.generated.gcs_service_pb2")
        gcs_service_pb2_grpc = importlib.import_module("ray.core.generated.gcs_service_pb2_grpc")
    except ImportError:
        return  # no grpcio or Ray: the probe's gRPC stage does not run (the rllib extra)
    from poc_env.agents.rl.cluster import probe

    servicer: Any = gcs_service_pb2_grpc.NodeInfoGcsServiceServicer

    class Gcs(servicer):  # type: ignore[misc,valid-type]
        def GetClusterId(self, request: Any, context: Any) -> Any:
            if fake == "other_unauthenticated":
                context.abort(grpc.StatusCode.UNAUTHENTICATED, "token required")
            return gcs_service_pb2.GetClusterIdReply()

    srv = grpc.server(futures.ThreadPoolExecutor(1))
    if fake != "no_service":
        gcs_service_pb2_grpc.add_NodeInfoGcsServiceServicer_to_server(Gcs(), srv)
    port = srv.add_insecure_port("127.0.0.1:0")
    srv.start()
    try:
        probe(("ray://" if client else "") + f"127.0.0.1:{port}", timeout_s=1.0)
    finally:
        srv.stop(0)
    raise SilentWrong(f"a gRPC server that is not Ray ({fake}) passed the probe")


def _run_curve(damage: str, points: list[tuple[int, float]], until: int | None) -> None:
    """``poc-env curve`` of a run folder whose TensorBoard log holds hostile steps and values,
    damaged or not: a PNG, or a clear error."""
    from torch.utils.tensorboard import SummaryWriter

    from poc_env.agents.rl.curve import plot_training_curve

    with tempfile.TemporaryDirectory() as d:
        run = Path(d)
        with SummaryWriter(str(run / "tb" / "ppo_1")) as w:
            for step, value in points:
                w.add_scalar("rollout/posc_mean", value, step)
        log = next((run / "tb" / "ppo_1").glob("events.out.tfevents.*"))
        data = log.read_bytes()
        damaged = {
            "none": data,
            "truncated": data[: max(0, len(data) - 7)],
            "garbage": bytes(range(256)) * 2,
            "empty": b"",
            "flipped": data[:60] + bytes([data[60] ^ 0xFF]) + data[61:] if len(data) > 61 else data,
        }
        log.write_bytes(damaged[damage])
        out = plot_training_curve(run, run / "curve.png", until)
        check(out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", "curve wrote no PNG")


def _run_nested_json(depth: int, opener: str, leaf: str) -> None:
    from poc_env.io import MAX_JSON_DEPTH, loads_json

    closer = "]" if opener == "[" else "}"
    text = opener * depth + leaf + closer * depth
    data = loads_json(text, "doc")  # a ConfigError, never a RecursionError
    check(depth <= MAX_JSON_DEPTH, f"JSON {depth} deep accepted")
    check(leaf not in ("NaN", "Infinity", "-Infinity"), f"{leaf} accepted as JSON")
    check(data is not None, "nothing parsed")


def _run_heading(actions: np.ndarray) -> None:
    """``-Heading-v1`` flies an out-of-Box action as its clipped one (``-v0`` normalised it)."""
    import gymnasium

    import poc_env  # noqa: F401  (registers the tasks)

    def first(a: np.ndarray) -> np.ndarray:
        env = gymnasium.make("poc_env/UAVSearch-Small-Heading-v1", disable_env_checker=True)
        env.reset(seed=5)
        obs, *_ = env.step(a)
        env.close()
        return obs

    got, want = first(actions), first(np.clip(actions, -1.0, 1.0))
    check(bool(np.all(np.isfinite(got))), "observation not finite")
    check(np.array_equal(got, want), "an out-of-Box heading flew unlike its clipped action")


# --------------------------------------------------------------------------- target: geo

_AREA = [[126.2, 45.4], [127.4, 45.4], [127.4, 46.2], [126.2, 46.2], [126.2, 45.4]]
_FIELDS = [("ZYHB", [126.25, 45.623]), ("Acheng", [126.95, 45.25])]
_CSV = [(45.8, 126.9, 0.3), (45.76, 126.98, 0.25), (45.72, 127.05, 0.2)]


def geo_strategy():
    from hypothesis import strategies as st

    coord = st.one_of(
        st.floats(-200, 200),
        st.sampled_from([float("nan"), float("inf"), 1e308, "45", None, 90.5, -181.0]),
    )
    ring = st.one_of(
        st.just(_AREA),
        st.just(_AREA),
        st.just(_AREA),
        st.just(_AREA[::-1]),  # clockwise
        st.just([[126.2, 45.4], [127.4, 46.2], [127.4, 45.4], [126.2, 46.2], [126.2, 45.4]]),
        st.just([[45.4, 126.2], [45.4, 127.4], [46.2, 127.4], [46.2, 126.2], [45.4, 126.2]]),
        st.lists(st.lists(coord, min_size=2, max_size=3), max_size=6),
        hostile_scalars(),
    )
    good_point = st.sampled_from([p for _, p in _FIELDS])
    point = st.one_of(good_point, good_point, good_point, st.lists(coord, max_size=3))
    csv_row = st.one_of(
        st.sampled_from(_CSV),
        st.sampled_from(_CSV),
        st.tuples(coord, coord, st.one_of(st.floats(-1, 2), coord)),
    )
    good_csv = "lat,lon,probability\n" + "".join(f"{a},{b},{c}\n" for a, b, c in _CSV)
    csv_text = st.one_of(
        st.just(good_csv),
        st.just(good_csv),
        st.lists(csv_row, min_size=0, max_size=4).map(
            lambda rows: "lat,lon,probability\n" + "".join(f"{a},{b},{c}\n" for a, b, c in rows)
        ),
        st.sampled_from(["", "lat,lon\n45.8,126.9\n", "x,y,z\n1,2,3\n", "\x00\x01"]),
    )
    cell = st.one_of(st.just(5.0), st.just(5.0), st.floats(0.001, 500), hostile_scalars())
    # names and properties of the GIS files (HOSTILE_TEXT), and malformed bytes in their place
    names = st.one_of(st.just("area"), st.just("area"), st.sampled_from(_GEO_STEMS))
    field_name = st.one_of(st.just("A"), st.just("A"), st.sampled_from(HOSTILE_TEXT))
    raw = st.one_of(st.none(), st.none(), st.none(), st.sampled_from(MALFORMED_GIS))
    return st.tuples(
        ring,
        point,
        st.one_of(csv_text, st.sampled_from(EXTREME_CSV)),
        cell,
        st.sampled_from(["aeqd", "utm", "merc"]),
        names,
        field_name,
        raw,
    )


#: CSV priors at the ends of float range: sums past 1.8e308, subnormals, 1e400 (-> inf).
EXTREME_CSV = [
    "lat,lon,probability\n45.8,126.9,1e308\n45.76,126.98,1e308\n",
    "lat,lon,probability\n45.8,126.9,1.7e308\n45.76,126.98,1.7e308\n45.72,127.05,1e308\n",
    "lat,lon,probability\n45.8,126.9,5e-324\n45.76,126.98,5e-324\n",
    "lat,lon,probability\n45.8,126.9,1e-308\n45.76,126.98,1e308\n",
    "lat,lon,probability\n45.8,126.9,1e400\n",
    "lat,lon,probability\n1e400,126.9,1\n",
]
#: Malformed bytes in place of one GIS file: (which file, its suffix, the bytes).
MALFORMED_GIS = [
    ("area", ".geojson", b"\x89PNG\r\n\x1a\n\x00\xff\xfe" * 20),
    (
        "area",
        ".geojson",
        b'{"type":"Polygon","coordinates":[[[1e400,45.4],[127.4,45.4],[127.4,46.2],[1e400,45.4]]]}',
    ),
    ("area", ".geojson", b'{"type":"Polygon","coordinates":' + b"[" * 50000 + b"]" * 50000 + b"}"),
    ("area", ".geojson", b'{"type":"Polygon","coordinates":[[[126.2,45.4],[127.4'),
    ("area", ".kml", b"\xff\xfe<\x00k\x00m\x00l\x00>"),
    (
        "area",
        ".kml",
        b"<kml><Placemark><Polygon><outerBoundaryIs><LinearRing><coordinates>"
        b"1e400,45.4 127.4,45.4 127.4,46.2</coordinates></LinearRing></outerBoundaryIs></Polygon>"
        b"</Placemark></kml>",
    ),
    ("prior", ".csv", b"\x00\x01\x02\xff\xfe\xfd" * 50),
    ("prior", ".csv", "lat,lon,probability\n45.8,126.9,0.3\n# caf\xe9\n".encode("latin-1")),
    ("prior", ".tif", b"II*\x00" + b"\xff" * 300),
    ("prior", ".tif", b"MM\x00*\x00\x00\x00\x08" + b"\x00" * 40),
    ("fields", ".geojson", b'\xef\xbb\xbf{"type": "FeatureCollection"}'),
]
_GEO_STEMS = ["a\nb: 1\nmap: {}", f"<{INJECTED_TAG}>", "q'\"&#", "ünï 漢", "x\u2028y"]


def run_geo(case: tuple) -> None:
    """``scenario import`` of hostile GIS layers; an accepted scenario loads, its prior sums to
    1, and its airfields sit where pyproj puts them."""
    import yaml

    from poc_env.agents.mission.geoimport import import_scenario, write_imported
    from poc_env.config import load_scenario
    from poc_env.theory.probability_map import build_prior

    ring, point, csv_text, cell, projection, stem, field_name, raw = case

    def fc(features: list) -> str:
        return json.dumps({"type": "FeatureCollection", "features": features}, allow_nan=True)

    with tempfile.TemporaryDirectory() as d:
        root = Path(d)
        paths = {
            "area": root / f"{stem}.geojson",
            "fields": root / "fields.geojson",
            "prior": root / "prior.csv",
        }
        paths["area"].write_text(
            fc([{"type": "Feature", "properties": {"name": field_name},
                 "geometry": {"type": "Polygon", "coordinates": [ring]}}]), encoding="utf-8"
        )  # fmt: skip
        paths["fields"].write_text(
            fc([{"type": "Feature", "properties": {"name": field_name},
                 "geometry": {"type": "Point", "coordinates": point}},
                {"type": "Feature", "properties": {"name": "B"},
                 "geometry": {"type": "Point", "coordinates": _FIELDS[1][1]}}]),
            encoding="utf-8",
        )  # fmt: skip
        paths["prior"].write_text(csv_text, encoding="utf-8")
        if raw is not None:
            which, suffix, data = raw
            paths[which] = root / f"bad_{which}{suffix}"
            paths[which].write_bytes(data)
        res = import_scenario(
            paths["area"],
            prior=paths["prior"],
            airfields=paths["fields"],
            cell_km=cell,
            name="fuzz",
            projection=projection,
        )
        write_imported(res, root / "fuzz.yaml")
        with open(root / "fuzz.yaml", encoding="utf-8") as fh:
            doc = yaml.safe_load(fh)
        check(set(doc) == set(res["scenario"]), f"YAML keys changed: {sorted(doc)}")
        check(doc == yaml.safe_load(yaml.safe_dump(res["scenario"])), "YAML differs")
        sc = load_scenario(str(root / "fuzz.yaml"))
        prior = build_prior(sc.map)
        check(abs(float(prior.sum()) - 1.0) < 1e-9, f"imported prior sums to {prior.sum()!r}")
        for a in sc.airfields:
            check(all(math.isfinite(v) for v in a.position_m), "airfield not finite")


# --------------------------------------------------------------------------- target: datafiles


def datafiles_strategy():
    """Velocity fields, particle files, DEMs and replan tracks (:mod:`.campaign_files`)."""
    from poc_env.agents.testing.campaign_files import datafiles_strategy as strategy

    return strategy()


def run_datafiles(case: tuple) -> None:
    from poc_env.agents.testing.campaign_files import run_datafiles as run

    run(case)


# --------------------------------------------------------------------------- the campaign

TARGETS: dict[str, tuple[Callable[[], Any], Callable[[Any], None]]] = {
    "overrides": (overrides_strategy, run_overrides),
    "maps": (maps_strategy, run_maps),
    "regions": (regions_strategy, run_regions),
    "plans": (plans_strategy, run_plans),
    "cli": (cli_strategy, run_cli),
    "actions": (actions_strategy, run_actions),
    "geo": (geo_strategy, run_geo),
    "text": (text_strategy, run_text),
    "utm": (utm_strategy, run_utm),
    "runtime": (runtime_strategy, run_runtime),
    "episodes": (episodes_strategy, run_episodes),
    "datafiles": (datafiles_strategy, run_datafiles),
}
#: Share of a campaign's cases per target (the CLI and region cases are the slow ones).
WEIGHTS = {
    "overrides": 3, "maps": 3, "regions": 1, "plans": 3, "cli": 1, "actions": 3, "geo": 1,
    "text": 2, "utm": 3, "runtime": 1, "episodes": 2, "datafiles": 1,
}  # fmt: skip


def _proc_stat(pid: int) -> tuple[int, str] | None:
    """(parent pid, state letter) of a live process, from /proc; None if gone."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    fields = stat[stat.rindex(")") + 2 :].split()  # the name in (...) may hold spaces
    return int(fields[1]), fields[0]


def orphans(tag: str | None = None) -> list[int]:
    """Pids of processes this one started that are still alive (zombies are reaped first):
    its descendants, and with ``tag`` any process whose environment carries
    ``POC_ENV_CAMPAIGN_TAG=tag`` (children whose parent died are re-parented to init).
    Reads /proc; an empty list where there is none."""
    me = os.getpid()
    with contextlib.suppress(ChildProcessError, OSError):
        while os.waitpid(-1, os.WNOHANG)[0]:  # reap finished children (no zombies counted)
            pass
    proc = Path("/proc")
    if not proc.is_dir():
        return []
    parents: dict[int, int] = {}
    for entry in proc.iterdir():
        if entry.name.isdigit() and (st := _proc_stat(int(entry.name))) and st[1] != "Z":
            parents[int(entry.name)] = st[0]
    found: set[int] = set()
    for pid in parents:
        p, seen = pid, set()
        while p in parents and p not in seen and p > 1:
            seen.add(p)
            p = parents[p]
            if p == me:
                found.add(pid)
                break
    if tag:
        marker = f"{TAG_VAR}={tag}".encode()
        for pid in parents.keys() - found - {me}:
            with contextlib.suppress(OSError):
                if marker in Path(f"/proc/{pid}/environ").read_bytes().split(b"\0"):
                    found.add(pid)
    return sorted(found)


def run_target(
    name: str, cases: int, seed: int = 0, timeout_s: float | None = CASE_TIMEOUT_S
) -> tuple[Counter, list[tuple[str, Any]]]:
    """Run ``cases`` hypothesis cases of target ``name``; (outcome counts, failing cases).
    A case still running after ``timeout_s`` seconds is stopped and counted as ``hang``."""
    from hypothesis import HealthCheck, Phase, given, settings
    from hypothesis import seed as hypothesis_seed

    strategy, fn = TARGETS[name]
    counts: Counter = Counter()
    bad: list[tuple[str, Any]] = []

    @hypothesis_seed(seed)
    @settings(
        max_examples=cases,
        database=None,
        deadline=None,
        suppress_health_check=list(HealthCheck),
        phases=[Phase.generate],
    )
    @given(strategy())
    def one(case: Any) -> None:
        outcome, detail = classify(fn, case, timeout_s)
        counts[outcome] += 1
        if outcome in BAD:
            bad.append((detail, case))

    one()
    return counts, bad


def build_parser() -> argparse.ArgumentParser:
    """The campaign's command line (``--help``: options, defaults, examples)."""
    from poc_env.helptext import HelpFormatter, examples

    p = argparse.ArgumentParser(
        prog="poc-env bench campaign",
        description=__doc__.split("\n")[0],
        formatter_class=HelpFormatter,
        epilog=examples(
            "poc-env bench campaign --cases 6500 --seed 72",
            "poc-env bench campaign --cases 500 --targets overrides,episodes --case-timeout 30",
        ),
    )
    p.add_argument("--cases", type=int, default=5000, help="total cases over all targets")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--targets", default=",".join(TARGETS))
    p.add_argument("--show", type=int, default=3, help="failing cases to print per target")
    p.add_argument(
        "--case-timeout",
        type=float,
        default=CASE_TIMEOUT_S,
        help="seconds one case may run before it counts as a hang (0: no limit)",
    )
    return p


def main(argv: list[str] | None = None) -> dict[str, Counter]:
    """Run the campaign and print the counts; each target's Counter also holds ``orphan``
    (processes it left alive) and ``seconds``."""
    import time

    p = build_parser()
    args = p.parse_args(argv)
    for name, lo, hi in (("cases", 1, MAX_CASES), ("show", 0, 10_000), ("seed", 0, 2**32 - 1)):
        v = getattr(args, name)
        if not lo <= v <= hi:  # 1e9 cases is days of work: refused up front
            p.error(f"--{name}: got {v}; allowed: an integer in [{lo}, {hi}]")
    if not (math.isfinite(args.case_timeout) and 0 <= args.case_timeout <= 86_400):
        p.error(f"--case-timeout: got {args.case_timeout}; allowed: seconds in [0, 86400]")
    names = [t for t in args.targets.split(",") if t]
    for t in names:
        if t not in TARGETS:
            p.error(f"--targets: got {t!r}; allowed: {', '.join(TARGETS)}")
    if not names:
        p.error("--targets: got none; allowed: " + ", ".join(TARGETS))
    tag = os.environ.setdefault(TAG_VAR, uuid.uuid4().hex)  # inherited by every child
    total_w = sum(WEIGHTS[t] for t in names)
    results: dict[str, Counter] = {}
    cols = ("tried", *OUTCOMES, "orphan")
    print(f"{'target':<10} " + " ".join(f"{o:>9}" for o in cols) + f" {'seconds':>8}")
    grand: Counter = Counter()

    def row(label: str, c: Counter, tried: int) -> str:
        return f"{label:<10} {tried:>9} " + " ".join(f"{c[o]:>9}" for o in (*OUTCOMES, "orphan"))

    for t in names:
        n = max(1, round(args.cases * WEIGHTS[t] / total_w))
        t0 = time.perf_counter()
        counts, bad = run_target(t, n, args.seed, args.case_timeout or None)
        tried = sum(counts.values())
        left = orphans(tag)
        counts["orphan"] = len(left)
        counts["seconds"] = round(time.perf_counter() - t0)
        results[t] = counts
        grand.update(counts)
        print(row(t, counts, tried) + f" {counts['seconds']:>8}", flush=True)
        for detail, case in bad[: args.show]:
            print(f"    {detail.strip().splitlines()[-1][:200]}\n      case: {case!r:.300}")
        for pid in left[: args.show]:
            with contextlib.suppress(OSError):
                cmd = Path(f"/proc/{pid}/cmdline").read_bytes().replace(bytes(1), b" ")
                print(f"    orphan {pid}: {cmd[:200]!r}")
    tried = sum(grand[o] for o in OUTCOMES)
    print(row("all", grand, tried) + f" {grand['seconds']:>8}")
    return results


def failed(results: dict[str, Counter]) -> bool:
    """True when a campaign's counts fail it (see :data:`BAD`, plus orphans)."""
    return any(c[o] for c in results.values() for o in (*BAD, "orphan"))


if __name__ == "__main__":  # pragma: no cover
    sys.exit(1 if failed(main()) else 0)
