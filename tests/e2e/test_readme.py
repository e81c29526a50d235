"""The README's Python examples run as written (so the user's manual stays true)."""

import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[2] / "README.md"
BLOCKS = re.findall(r"```python\n(.*?)```", README.read_text(encoding="utf-8"), flags=re.S)


def test_readme_has_python_examples():
    assert BLOCKS


@pytest.mark.parametrize("code", BLOCKS, ids=[f"block{k}" for k in range(len(BLOCKS))])
def test_readme_python_block_runs(code, capsys):
    exec(compile(code, str(README), "exec"), {"__name__": "__readme__"})
    assert capsys.readouterr().out.strip()


def test_readme_gis_walkthrough_runs_as_written(tmp_path):
    """'From a GIS to a ground station': the shell blocks, run verbatim with the installed
    ``poc-env``, give the scenario, a plan and six QGC missions plus a KML."""
    import os
    import shutil
    import subprocess
    import sys

    text = README.read_text(encoding="utf-8")
    section = text[text.index("## From a GIS to a ground station") :]
    setup = re.search(r"```\nmkdir walk && cd walk\n(.*?)```", section, flags=re.S)
    flight = re.search(r"```\n(poc-env plan --scenario harbin\.yaml.*?)```", section, flags=re.S)
    assert setup and flight
    exe = shutil.which("poc-env", path=str(Path(sys.executable).parent))
    assert exe is not None
    env = dict(os.environ, PATH=f"{Path(exe).parent}{os.pathsep}{os.environ['PATH']}")
    for block in (setup.group(1), flight.group(1)):
        done = subprocess.run(
            ["bash", "-e", "-c", block], cwd=tmp_path, env=env, capture_output=True, text=True,
            timeout=600, check=False,
        )  # fmt: skip
        assert done.returncode == 0, done.stderr[-2000:]
    out = tmp_path / "missions"
    assert sorted(p.name for p in out.iterdir()) == [
        "plan.html",
        "plan.kml",
        "plan_prior.png",
        *[f"plan_uav{k}.plan" for k in range(1, 7)],
    ]
    # the scenario's map.origin_deg gave the plan its CRS (no --origin in the walkthrough)
    import json

    plan = json.loads((tmp_path / "plan.json").read_text())
    assert plan["crs"]["origin_deg"] == [45.4, 126.2]
    for name in ("harbin.yaml", "harbin.npy", "harbin.crs.json", "plan.json"):
        assert (tmp_path / name).is_file(), name
