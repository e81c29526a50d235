"""The dependency rule of the layout, read from the source (imports inside functions included).

    base (errors, limits, io, geometry, config, _kernels) <- theory <- sim <- viz <- envs
    <- poc_env.agents.mission <- .planning <- .policies <- .rl <- .experiments / .benchmarks
    <- cli / .testing

A module may import its own layer and the layers below it, never one above. The layers are
listed once, here and in docs/ARCHITECTURE.md; a new module must be placed in one. And no
module imports itself back, however indirectly: the import graph has no cycles.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: (prefix, rank): the longest matching prefix of a dotted module name gives its layer.
LAYERS = (
    ("poc_env.errors", 0),
    ("poc_env.io", 0),
    ("poc_env.geometry", 0),
    ("poc_env.crs", 0),  # local metres <-> lat/lon (pyproj): export, import, velocity fields
    ("poc_env.config", 0),
    ("poc_env.limits", 0),
    ("poc_env.spec", 0),
    ("poc_env.stats", 0),
    ("poc_env.helptext", 0),
    ("poc_env._kernels", 0),
    ("poc_env.theory", 1),
    ("poc_env.sim", 2),
    ("poc_env.viz", 3),
    ("poc_env.envs", 4),
    ("poc_env.uav_search_v0", 4),
    ("poc_env.uav_search_v1", 4),
    ("poc_env.recorded", 4),
    ("poc_env", 4),  # the package's __init__: parallel_env, env, registration
    # geography in, missions out: the plan model, the CRS, every export format, GIS import
    ("poc_env.agents.mission", 5),
    ("poc_env.agents.planning", 6),
    ("poc_env.agents.policies", 7),
    ("poc_env.agents.rl", 8),
    ("poc_env.agents.experiments", 9),
    ("poc_env.agents.benchmarks", 9),
    ("poc_env.agents", 9),
    ("poc_env.cli", 10),
    # test harnesses (the hostile-input campaign) drive every input, the command line included
    ("poc_env.agents.testing", 10),
)
NAMES = {0: "base", 1: "theory", 2: "sim", 3: "viz", 4: "envs", 5: "mission", 6: "planning"}
NAMES |= {7: "policies", 8: "rl", 9: "experiments", 10: "cli"}

#: What the planners may use of the mission package: the plan model and the CRS, no exporter.
PLANNING_MAY_IMPORT = (
    "poc_env.agents.mission.plan",
    "poc_env.agents.mission.crs",
    "poc_env.agents.mission.terrain",  # the ground under the plan, as the CRS places it
)


def layer(module: str) -> int:
    best = max((p for p, _ in LAYERS if module == p or module.startswith(p + ".")), key=len)
    return dict(LAYERS)[best]


def modules() -> list[tuple[str, Path]]:
    out = []
    # agents/ installs as poc_env.agents (poc_env/agents is a link to it): walked once, as that
    for pkg, dotted in (("poc_env", ("poc_env",)), ("agents", ("poc_env", "agents"))):
        for f in sorted((ROOT / pkg).rglob("*.py")):
            rel = f.relative_to(ROOT / pkg)
            if pkg == "poc_env" and rel.parts[0] == "agents":
                continue
            parts = (*dotted, *rel.with_suffix("").parts)
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            out.append((name, f))
    return out


def project_imports(module: str, path: Path) -> list[tuple[int, str]]:
    """(line, imported module) for every import of poc_env or agents in ``path``."""
    found = []
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:  # relative: resolve against the package
                base = package.split(".")
                base = base[: len(base) - node.level + 1]
                stem = ".".join([*base, node.module] if node.module else base)
            else:
                stem = node.module or ""
            # `from pkg import sub` imports the submodule pkg.sub when there is one
            names = [stem] + [f"{stem}.{a.name}" for a in node.names]
            names = [n for n in names if n == stem or _is_module(n)]
        else:
            continue
        found += [(node.lineno, n) for n in names if n.split(".")[0] == "poc_env"]
    return found


def _is_module(dotted: str) -> bool:
    p = ROOT.joinpath(*dotted.split("."))
    return p.with_suffix(".py").exists() or (p / "__init__.py").exists()


def test_every_module_has_a_layer():
    mods = modules()
    assert len(mods) > 40  # the walk found the packages
    for name, _ in mods:
        assert layer(name) in NAMES, name


@pytest.mark.parametrize("name,path", modules(), ids=[m for m, _ in modules()])
def test_imports_respect_layers(name, path):
    mine = layer(name)
    bad = [
        f"{path.relative_to(ROOT)}:{line} imports {target} ({NAMES[layer(target)]}) "
        f"from the {NAMES[mine]} layer"
        for line, target in project_imports(name, path)
        if layer(target) > mine
    ]
    assert not bad, "\n".join(bad)


def test_rule_catches_an_upward_import(tmp_path):
    """The checker itself: an import of agents from the simulator is reported."""
    src = tmp_path / "core.py"
    src.write_text("def f():\n    from poc_env.agents.planning import planner\n", encoding="utf-8")
    found = project_imports("poc_env.sim.core", src)
    assert found == [(2, "poc_env.agents.planning"), (2, "poc_env.agents.planning.planner")]
    assert max(layer(t) for _, t in found) > layer("poc_env.sim.core")


def test_nothing_below_the_cli_imports_agents():
    offenders = [
        f"{name}: {t}"
        for name, path in modules()
        if layer(name) < layer("poc_env.agents.mission")
        for _, t in project_imports(name, path)
        if t.startswith("poc_env.agents")
    ]
    assert not offenders, offenders


def test_planning_needs_no_exporter():
    """Planners build plans with the plan model and the CRS; exporters are not theirs."""
    offenders = [
        f"{name}:{line} imports {t}"
        for name, path in modules()
        if name.startswith("poc_env.agents.planning")
        for line, t in project_imports(name, path)
        if t.startswith("poc_env.agents.mission") and t not in PLANNING_MAY_IMPORT
    ]
    assert not offenders, offenders


def graph_imports(module: str, path: Path) -> set[str]:
    """The project modules ``path`` imports, as edges of the import graph: as
    :func:`project_imports`, except that ``from pkg import sub`` of submodules only is an edge to
    each ``pkg.sub``, not to ``pkg`` (Python runs every parent package first anyway; naming one
    is no dependency on its ``__init__``)."""
    found = set()
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - node.level + 1]
                stem = ".".join([*base, node.module] if node.module else base)
            else:
                stem = node.module or ""
            subs = [f"{stem}.{a.name}" for a in node.names if _is_module(f"{stem}.{a.name}")]
            names = subs if len(subs) == len(node.names) else [stem, *subs]
        else:
            continue
        found |= {n for n in names if n.split(".")[0] == "poc_env"}
    return found


def import_graph(mods: list[tuple[str, Path]]) -> dict[str, set[str]]:
    """module -> the project modules it imports (lazy imports included, itself excluded)."""
    names = {name for name, _ in mods}
    return {
        name: {t for t in graph_imports(name, path) if t in names and t != name}
        for name, path in mods
    }


def cycles(graph: dict[str, set[str]]) -> list[frozenset[str]]:
    """The import cycles of ``graph``: its strongly connected components of two or more
    modules (Tarjan's algorithm, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[frozenset[str]] = []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph.get(child, ())))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
            if low[node] == index[node]:
                scc = set()
                while True:
                    m = stack.pop()
                    on_stack.discard(m)
                    scc.add(m)
                    if m == node:
                        break
                if len(scc) > 1:
                    found.append(frozenset(scc))
    return found


def test_no_import_cycles():
    """No module imports itself back through others (imports inside functions included)."""
    found = list(cycles(import_graph(modules())))
    assert not found, "import cycles: " + "; ".join(" <-> ".join(sorted(c)) for c in found)


def test_cycle_check_catches_a_cycle(tmp_path):
    """The checker itself: two modules importing each other, one lazily, are a cycle; a chain
    is not."""
    a, b, c = tmp_path / "a.py", tmp_path / "b.py", tmp_path / "c.py"
    a.write_text("from poc_env.agents.mission import plan\n", encoding="utf-8")
    b.write_text("def f():\n    import poc_env.agents.mission.export\n", encoding="utf-8")
    c.write_text("import poc_env.agents.mission.export\n", encoding="utf-8")
    mods = [
        ("poc_env.agents.mission.export", a),  # export -> plan
        ("poc_env.agents.mission.plan", b),  # plan -> export, inside a function
        ("poc_env.agents.mission.crs", c),  # crs -> export: no way back
    ]
    graph = import_graph(mods)
    assert graph["poc_env.agents.mission.plan"] == {"poc_env.agents.mission.export"}
    assert cycles(graph) == [
        frozenset({"poc_env.agents.mission.export", "poc_env.agents.mission.plan"})
    ]
    assert cycles({"x": {"y"}, "y": {"z"}, "z": set()}) == []
