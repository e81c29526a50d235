"""The dependency rule of the layout, read from the source (imports inside functions included).

    base (errors, limits, io, geometry, config, _kernels) <- theory <- sim <- viz <- envs
    <- poc_env.agents.planning <- .policies <- .rl <- .experiments / .benchmarks <- cli / .testing

A module may import its own layer and the layers below it, never one above. The layers are
listed once, here and in docs/ARCHITECTURE.md; a new module must be placed in one.
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
    ("poc_env.config", 0),
    ("poc_env.limits", 0),
    ("poc_env.spec", 0),
    ("poc_env._kernels", 0),
    ("poc_env.theory", 1),
    ("poc_env.sim", 2),
    ("poc_env.viz", 3),
    ("poc_env.envs", 4),
    ("poc_env.uav_search_v0", 4),
    ("poc_env.recorded", 4),
    ("poc_env", 4),  # the package's __init__: parallel_env, env, registration
    ("poc_env.agents.planning", 5),
    ("poc_env.agents.policies", 6),
    ("poc_env.agents.rl", 7),
    ("poc_env.agents.experiments", 8),
    ("poc_env.agents.benchmarks", 8),
    ("poc_env.agents", 8),
    ("poc_env.cli", 9),
    # test harnesses (the hostile-input campaign) drive every input, the command line included
    ("poc_env.agents.testing", 9),
)
NAMES = {0: "base", 1: "theory", 2: "sim", 3: "viz", 4: "envs", 5: "planning"}
NAMES |= {6: "policies", 7: "rl", 8: "experiments", 9: "cli"}


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
        if layer(name) < layer("poc_env.agents.planning")
        for _, t in project_imports(name, path)
        if t.startswith("poc_env.agents")
    ]
    assert not offenders, offenders
