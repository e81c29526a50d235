"""A griffe extension for the API reference (mkdocs.yml, mkdocstrings ``extensions``).

The docstrings are numpydoc written for Sphinx and ``help()``: Sphinx roles (:func:`x`,
:class:`~a.b.C`, :mod:`x`), reST simple tables (``====  ====`` borders) and ``::`` literal
blocks. Markdown would show a role's name, run a table's rows together and reflow a literal
block, so when an object is loaded its docstring is rewritten for the site only: a role becomes
inline code of its target (``~`` keeps the last name, as Sphinx shows it), a simple table and a
literal block become preformatted blocks. The source docstrings stay as they are."""

from __future__ import annotations

import re

import griffe

ROLE = re.compile(r":(?:py:)?(?:func|class|mod|meth|attr|data|obj|exc|const|term|ref):`([^`]+)`")
BORDER = re.compile(r"^\s*=+(\s+=+)+\s*$")


def _role(match: re.Match[str]) -> str:
    text = match.group(1).strip()
    label = re.match(r"(.*?)\s*<(.+)>$", text)  # :ref:`label <target>`
    if label:
        return f"`{label.group(1)}`"
    if text.startswith("~"):
        text = text[1:].rsplit(".", 1)[-1]
    return f"`{text}`"


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip())


def _blocks(text: str) -> str:
    """Fence reST simple tables and ``::`` literal blocks."""
    lines = text.split("\n")
    out: list[str] = []
    i = 0
    while i < len(lines):
        line = lines[i]
        if BORDER.match(line):  # a simple table: up to the border followed by a blank or the end
            pad = " " * _indent(line)
            j = i + 1
            while j < len(lines) and not (
                BORDER.match(lines[j]) and (j + 1 == len(lines) or not lines[j + 1].strip())
            ):
                j += 1
            out += [f"{pad}```text", *lines[i : j + 1], f"{pad}```"]
            i = j + 1
            continue
        if (
            line.rstrip().endswith("::")
            and not line.rstrip().endswith(" ::")
            and line.strip() != "::"
        ):
            base = _indent(line)
            j = i + 1
            while j < len(lines) and not lines[j].strip():
                j += 1
            k = j
            while k < len(lines) and (not lines[k].strip() or _indent(lines[k]) > base):
                k += 1
            while k > j and not lines[k - 1].strip():
                k -= 1
            if k > j:  # an indented block follows
                pad = " " * base
                body = [ln[base:] if ln.strip() else "" for ln in lines[j:k]]
                out += [line.rstrip()[:-1], "", f"{pad}```text", *[pad + b for b in body],
                        f"{pad}```"]  # fmt: skip
                i = k
                continue
        out.append(line)
        i += 1
    return "\n".join(out)


class SphinxRoles(griffe.Extension):
    """Rewrite every docstring for Markdown when its object is loaded."""

    def on_instance(self, *, obj: griffe.Object, **kwargs: object) -> None:
        doc = obj.docstring
        if doc is None:
            return
        value = ROLE.sub(_role, doc.value) if ":" in doc.value else doc.value
        if "==" in value or "::" in value:
            value = _blocks(value)
        doc.value = value
