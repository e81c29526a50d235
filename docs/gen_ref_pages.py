"""Generate the API reference pages at build time (mkdocs-gen-files): one page per module of
the installed package ``poc_env`` (``poc_env.agents`` included: poc_env/agents links to the
top-level agents/ folder), found by walking the source tree, and a literate-nav SUMMARY.md.
A module moved, added or removed needs no hand edit here or in mkdocs.yml."""

import os
from pathlib import Path

import mkdocs_gen_files

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "poc_env"
SKIP_DIRS = {"__pycache__", "configs", "checkpoints", "assets"}

nav = mkdocs_gen_files.Nav()
modules = []
for folder, dirs, files in os.walk(PACKAGE, followlinks=True):
    here = Path(folder)
    # a folder is a package only with an __init__.py; skip data and cache folders
    dirs[:] = sorted(d for d in dirs if d not in SKIP_DIRS and (here / d / "__init__.py").is_file())
    for name in sorted(files):
        if not name.endswith(".py") or name == "__main__.py":
            continue
        parts = list((here / name).relative_to(PACKAGE.parent).with_suffix("").parts)
        if any(p.startswith("_") and p != "__init__" for p in parts):
            continue  # private modules (the compiled kernels) stay out of the reference
        modules.append(parts)

for parts in sorted(modules):
    if parts[-1] == "__init__":
        parts = parts[:-1]
        doc = Path("reference", *parts, "index.md")
    else:
        doc = Path("reference", *parts).with_suffix(".md")
    nav[tuple(parts)] = doc.relative_to("reference").as_posix()
    with mkdocs_gen_files.open(doc, "w") as fd:
        fd.write(f"::: {'.'.join(parts)}\n")
    mkdocs_gen_files.set_edit_path(doc, Path("..", *parts).as_posix() + ".py")

with mkdocs_gen_files.open("reference/SUMMARY.md", "w") as fd:
    fd.writelines(nav.build_literate_nav())
