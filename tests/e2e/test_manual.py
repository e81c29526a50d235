"""A newcomer's audit of the manual (docs-audit): what the README and the documentation site
state about the project agrees with the project's own files. The dependency table of
docs/index.md against pyproject.toml's dependencies and extras."""

from __future__ import annotations

import importlib
import re
from pathlib import Path

import pytest

tomllib = pytest.importorskip("tomllib")  # Python 3.11+ (pyproject.toml is read as it is)

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"


def _name(requirement: str) -> str:
    """The normalised distribution name of a requirement (``ray[rllib]>=2.50`` -> ``ray``)."""
    return re.split(r"[\s\[<>=!~;(]", requirement.strip(), maxsplit=1)[0].lower().replace("_", "-")


def _groups() -> dict[str, set[str]]:
    """Each group of pyproject.toml (``core`` and every extra) and the packages it lists itself
    (a ``poc-env[...]`` inclusion of other extras is not a package)."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    groups = {"core": {_name(r) for r in project["dependencies"]}}
    for extra, reqs in project["optional-dependencies"].items():
        groups[extra] = {_name(r) for r in reqs if _name(r) != "poc-env"}
    return groups


def _dependency_table() -> list[tuple[set[str], set[str]]]:
    """The rows of docs/index.md's dependency table: (packages, the groups named in the row's
    group cell: ``core`` or the back-quoted extras)."""
    text = (DOCS / "index.md").read_text(encoding="utf-8")
    section = text[text.index("## Dependencies") :]
    section = section[: section.index("\n## ", 1)]
    rows = []
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 3 or cells[0] in ("package", "") or set(cells[0]) <= set("-: "):
            continue
        names = re.split(r",(?![^\[]*\])", re.sub(r"\([^)]*\)", "", cells[0]))
        packages = {_name(n) for n in names} - {"poc-env"}  # poc-env[...]: other extras
        groups = set(re.findall(r"`([\w-]+)`", cells[1])) | ({"core"} & set(cells[1].split()))
        rows.append((packages, groups))
    return rows


def test_dependency_table_matches_pyproject():
    """Every package of pyproject.toml's core and extras has a row in the table, under a group
    that lists it; every row names packages that group still lists; every extra is in the table
    (audit docs-audit: lxml, jinja2, pillow and jsonschema, core dependencies since the mission
    export and the campaign, had no row, and pillow's row said the core never loads it)."""
    groups = _groups()
    rows = _dependency_table()
    assert rows
    wrong = []
    for packages, named in rows:
        assert named, f"a row with no group: {packages}"
        for pkg in packages:
            if not any(pkg in groups.get(g, set()) for g in named):
                wrong.append(
                    f"{pkg}: row says {sorted(named)}, pyproject lists it in "
                    f"{sorted(g for g, ps in groups.items() if pkg in ps) or 'none'}"
                )
    in_table = {pkg: named for packages, named in rows for pkg in packages}
    for group, packages in groups.items():
        for pkg in sorted(packages):
            if pkg not in in_table:
                wrong.append(f"{pkg} ({group}): no row in docs/index.md's dependency table")
    named_groups = set().union(*(named for _, named in rows))
    wrong += [f"extra {g!r}: not in the table" for g in groups if g not in named_groups]
    assert not wrong, "\n".join(wrong)


def test_readme_names_every_extra():
    """The README's install section names every extra of pyproject.toml (it left out `ocean`,
    `all` and `bench`)."""
    readme = " ".join((ROOT / "README.md").read_text(encoding="utf-8").split())
    section = readme[readme.index("## Install") : readme.index("## The environment in")]
    named = set(re.findall(r"`([\w-]+)`", section))
    assert sorted(set(_groups()) - {"core"} - named) == []


def _dotted_names() -> dict[str, str]:
    """Every ``poc_env.a.b`` name the README and the pages cite, with where it is first cited."""
    found: dict[str, str] = {}
    for page in [ROOT / "README.md", *sorted(DOCS.glob("*.md"))]:
        text = page.read_text(encoding="utf-8")
        for m in re.finditer(r"\bpoc_env(?:\.\w+)+", text):
            line = text.count("\n", 0, m.start()) + 1
            found.setdefault(m.group(0), f"{page.relative_to(ROOT)}:{line}")
    return found


def _resolves(name: str) -> bool:
    """``name`` is a module, or an attribute chain of the longest module it starts with."""
    parts = name.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ModuleNotFoundError:
            continue
        for attr in parts[i:]:
            if not hasattr(obj, attr):
                return False
            obj = getattr(obj, attr)
        return True
    return False


def test_every_cited_python_name_exists():
    """A reader who looks up a ``poc_env....`` name the manual cites finds it (audit docs-audit:
    docs/BENCHMARKS.md cited ``poc_env._kernels.swarm.kinematics``, which lives in
    ``poc_env._kernels.sensing``, and ``poc_env.theory.bound.reach_effort_bound``, which is
    ``poc_env.agents.experiments.evaluate.reach_effort_bound``)."""
    names = _dotted_names()
    assert len(names) > 50
    missing = [f"{where}: {name}" for name, where in sorted(names.items()) if not _resolves(name)]
    assert not missing, "\n".join(missing)


#: a command line as the pages write one: back-quoted or on a line of a fenced block
COMMAND = re.compile(r"`(?:[A-Z_]+=\S+ )*(?:poc-env|python|make) [^`]+`|^(?:poc-env|python) ", re.M)
IMAGE = re.compile(r"!\[[^\]]*\]\(([^)\s]+)\)")


def _images() -> list[tuple[str, str, str]]:
    """(where, image path, the text around it: ten lines either side, image links removed) of
    every image of the README and the pages."""
    found = []
    for page in [ROOT / "README.md", *sorted(DOCS.glob("*.md"))]:
        lines = page.read_text(encoding="utf-8").splitlines()
        for i, line in enumerate(lines):
            for m in IMAGE.finditer(line):
                near = "\n".join(lines[max(0, i - 10) : i + 11])
                where = f"{page.relative_to(ROOT)}:{i + 1}"
                found.append((where, m.group(1).replace("../", ""), IMAGE.sub("", near)))
    return found


def test_every_image_is_named_with_the_command_that_makes_it():
    """Every figure of the README and the manual exists and, within ten lines, a command that
    makes it is written out together with the image's file (its name, or its folder as the
    command's ``--out``) ("every figure in them is produced by a command in the repo"; audit
    docs-audit: 18 of 34 images had no such line near them, e.g. the theory page's pattern
    gallery of ``poc-env figures``)."""
    images = _images()
    assert len(images) > 20
    unnamed = []
    for where, image, near in images:
        assert (ROOT / image).is_file(), f"{where}: {image} does not exist"
        path = Path(image)
        names = (path.name, path.parent.as_posix() + " ", path.parent.as_posix() + "`")
        if not COMMAND.search(near) or not any(n in near for n in names):
            unnamed.append(f"{where}: {image}")
    assert not unnamed, "no command named beside:\n" + "\n".join(unnamed)


def _command_lines() -> list[tuple[str, str]]:
    """(where, line) of every ``poc-env ...`` command the README and the pages write: each line
    of a fenced block (continuations joined) and each back-quoted span."""
    found = []
    for page in [ROOT / "README.md", *sorted(DOCS.glob("*.md"))]:
        text = page.read_text(encoding="utf-8")
        fence = re.compile(r"^```\w*\n(.*?)^```", flags=re.S | re.M)
        for m in fence.finditer(text):
            where = f"{page.relative_to(ROOT)}:{text.count(chr(10), 0, m.start()) + 2}"
            for line in m.group(1).replace("\\\n", " ").splitlines():
                for part in re.split(r"&&|;|\|(?=\s*\w)", line):
                    i = part.find("poc-env ")
                    if i >= 0 and (i == 0 or part[i - 1] in " /(\t"):
                        found.append((where, part[i:]))  # the block's first line
        prose = fence.sub("", text)
        for m in re.finditer(r"`(poc-env [^`]+)`", prose):
            found.append((f"{page.relative_to(ROOT)}", " ".join(m.group(1).split())))
    return found


def _flags_of() -> dict[str, set[str]]:
    """Every command path of ``poc-env`` (subcommands, ``scenario import``, each ``bench``
    benchmark, ``train``'s tyro options) and the option strings its parser takes (with the
    top-level options, which every command takes)."""
    import contextlib
    import io

    from poc_env.agents.rl.args import parse_train_args
    from poc_env.cli import BENCHMARKS, build_parser
    from poc_env.helptext import walk

    parsers = dict(walk(build_parser()))
    for name, module in BENCHMARKS.items():
        parsers[f"poc-env bench {name}"] = importlib.import_module(module).build_parser()
    top = set(parsers["poc-env"]._option_string_actions)
    flags = {path: set(p._option_string_actions) | top for path, p in parsers.items()}
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.suppress(SystemExit):
        parse_train_args(["--help"])
    flags["poc-env train"] = set(re.findall(r"--[a-z][\w-]*", out.getvalue())) | top
    return flags


def test_every_flag_in_the_manual_exists():
    """Every ``--flag`` of a ``poc-env`` command line in the README and the pages is an option of
    that command (its subcommand, ``scenario import``, the ``bench`` benchmark named, or
    ``train``'s generated options): a renamed or dropped option cannot stay documented."""
    flags = _flags_of()
    lines = _command_lines()
    assert len(lines) > 200
    wrong = []
    for where, line in lines:
        line = re.split(r"\s#|\s{2,}#", line)[0]
        words = line.replace("[", " ").replace("]", " ").replace("|", " ").split()
        if len(words) < 2 or not re.fullmatch(r"[a-z][\w-]*", words[1]):
            continue
        path, rest = f"poc-env {words[1]}", words[2:]
        if rest and not rest[0].startswith("-") and f"{path} {rest[0]}" in flags:
            path, rest = f"{path} {rest[0]}", rest[1:]
        if path not in flags:
            if words[1] not in ("command", "developers"):  # prose: "the poc-env command"
                wrong.append(f"{where}: {line}: no command {path!r}")
            continue
        for word in rest:
            flag = word.split("=")[0]
            if re.fullmatch(r"--[a-z][\w-]*", flag) and flag not in flags[path]:
                wrong.append(f"{where}: {line}: {path} has no {flag}")
    assert not wrong, "\n".join(wrong)


def _heading_ids(page: Path) -> set[str]:
    """The anchors of ``page`` as the site makes them (Python-Markdown's ``toc``, as mkdocs.yml
    configures it, with ``attr_list`` ids)."""
    import markdown

    md = markdown.Markdown(extensions=["toc", "attr_list", "tables", "admonition"])
    md.convert(page.read_text(encoding="utf-8"))
    ids: set[str] = set()
    todo = list(md.toc_tokens)  # type: ignore[attr-defined]
    while todo:
        token = todo.pop()
        ids.add(token["id"])
        todo += token["children"]
    return ids


def test_readme_anchors_lead_to_headings():
    """The README's links into the pages (``docs/tasks.md#baselines``) name a heading there (the
    strict site build checks the pages' own anchors, not the README's, which it does not read)."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    links = re.findall(r"\]\((docs/[^)#\s]+\.md)#([^)\s]+)\)", text)
    assert len(links) >= 4
    missing = [f"{page}#{anchor}" for page, anchor in links
               if anchor not in _heading_ids(ROOT / page)]  # fmt: skip
    assert not missing, missing
