"""MkDocs hooks of the documentation site (mkdocs.yml ``hooks:``).

Generated results live in the top-level results/ folder, outside docs/. The pages link them as
``../results/...`` (so they also render on a repository browser); at build time every file of
results/ except its Markdown is added to the site under ``results/``, and those links are
rewritten to point there."""

from __future__ import annotations

import posixpath
from pathlib import Path

from mkdocs.structure.files import File, Files

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "results"


def on_files(files: Files, config) -> Files:
    for path in sorted(RESULTS.rglob("*")):
        if path.is_file() and path.suffix != ".md":
            uri = "results/" + path.relative_to(RESULTS).as_posix()
            files.append(File.generated(config, uri, abs_src_path=str(path)))
    return files


def on_page_markdown(markdown: str, page, config, files) -> str:
    if "](../results/" not in markdown:
        return markdown
    here = posixpath.dirname(page.file.src_uri)
    target = posixpath.relpath("results", here or ".")
    return markdown.replace("](../results/", f"]({target}/")
