"""The README's Python examples run as written, and its links lead somewhere (the front door
stays true; the manual's pages are tested by tests/e2e/test_docs.py)."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
BLOCKS = re.findall(r"```python\n(.*?)```", README.read_text(encoding="utf-8"), flags=re.S)


def test_readme_has_python_examples():
    assert len(BLOCKS) == 2  # the environment in 10 lines, a plan in 5 lines


@pytest.mark.parametrize("code", BLOCKS, ids=[f"block{k}" for k in range(len(BLOCKS))])
def test_readme_python_block_runs(code, capsys):
    exec(compile(code, str(README), "exec"), {"__name__": "__readme__"})
    assert capsys.readouterr().out.strip()


def test_readme_links_and_figures_exist():
    """Every relative link and image of the README names a file of the repository (the site's
    own links are checked by the strict build, which does not read the README)."""
    text = README.read_text(encoding="utf-8")
    targets = re.findall(r"\]\(([^)\s]+)\)", text)
    local = [t.split("#")[0] for t in targets if not re.match(r"[a-z]+:", t)]
    assert local
    missing = [t for t in local if t and not (ROOT / t).exists()]
    assert not missing, missing


def test_readme_stays_a_front_door():
    """The README is the front door (about 15 KB at most); the manual is the docs site."""
    assert README.stat().st_size <= 15_500


def test_counts_of_tasks_match_the_registry():
    """The README and docs/environment.md say how many tasks are registered; the number follows
    the registry (it said 18 for three sessions after the registry had grown to 50)."""
    from poc_env.tasks import TASKS

    readme = " ".join(README.read_text(encoding="utf-8").split())
    env_doc = (ROOT / "docs" / "environment.md").read_text(encoding="utf-8")
    assert re.findall(r"\((\d+) registered tasks", readme) == [str(len(TASKS))]
    assert re.findall(r"\((\d+) tasks: every scenario", env_doc) == [str(len(TASKS))]
    # audit (i28-audit): the intro of docs/environment.md said 18, docs/tasks.md said 40
    tasks_doc = (ROOT / "docs" / "tasks.md").read_text(encoding="utf-8")
    assert re.findall(r"The (\d+) registered benchmark tasks", env_doc) == [str(len(TASKS))]
    assert re.findall(r"`poc-env tasks` lists (\d+) registered", tasks_doc) == [str(len(TASKS))]
