"""The docstrings' examples (numpydoc ``Examples`` sections, ``>>>``) run as doctests.

Every module of the installed package ``poc_env`` (``poc_env.agents`` included) whose source
holds an example is imported and its examples run; a module moved or added needs no edit here.
Examples compare their printed output exactly, with whitespace normalised and ``...``
allowed."""

import doctest
import importlib
import os
from pathlib import Path

import pytest

import poc_env

PACKAGE = Path(poc_env.__file__).resolve().parent
SKIP_DIRS = {"__pycache__", "configs", "checkpoints", "assets"}


def _modules_with_examples() -> list[str]:
    names = []
    for folder, dirs, files in os.walk(PACKAGE, followlinks=True):
        here = Path(folder)
        dirs[:] = sorted(
            d for d in dirs if d not in SKIP_DIRS and (here / d / "__init__.py").exists()
        )
        for name in sorted(files):
            path = here / name
            if name.endswith(".py") and ">>>" in path.read_text(encoding="utf-8"):
                parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
                names.append(".".join(parts[:-1] if parts[-1] == "__init__" else parts))
    return names


def _examples() -> list[doctest.DocTest]:
    finder = doctest.DocTestFinder(exclude_empty=True)
    tests = []
    for name in _modules_with_examples():
        module = importlib.import_module(name)
        tests += [t for t in finder.find(module, name) if t.examples]
    return sorted(tests, key=lambda t: t.name)


EXAMPLES = _examples()
FLAGS = doctest.NORMALIZE_WHITESPACE | doctest.ELLIPSIS


def test_there_are_examples():
    assert len(EXAMPLES) >= 5


@pytest.mark.parametrize("test", EXAMPLES, ids=[t.name for t in EXAMPLES])
def test_docstring_example(test):
    report: list[str] = []
    result = doctest.DocTestRunner(optionflags=FLAGS).run(test, out=report.append)
    assert result.failed == 0, "".join(report)
