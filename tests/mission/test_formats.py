"""The format table is the one list of export formats: the CLI offers it, the campaign exports
each entry, export_plan dispatches through it, and each writer names its files as listed."""

from __future__ import annotations

import json
import re
from importlib import metadata
from pathlib import Path

import pytest

from poc_env.agents.mission.export import export_plan
from poc_env.agents.mission.formats import FORMATS, Format
from poc_env.agents.mission.plan import load_plan, write_plan
from poc_env.agents.testing.campaign import OUTPUT_CHECKS, plans_strategy, sample_plan
from poc_env.cli import main

ORIGIN = "45.75,126.65"


def _file_names(fmt: Format, stem: str, ids: list) -> set[str]:
    return {stem + s.format(id=i) for s in fmt.suffixes for i in ids}


def test_the_cli_offers_every_registered_format(capsys):
    with pytest.raises(SystemExit):
        main(["export", "--help"])
    text = capsys.readouterr().out
    offered = re.search(r"--format \{([^}]*)\}", text)
    assert offered is not None and offered.group(1).split(",") == list(FORMATS)
    for f in FORMATS.values():
        assert f"{f.name}: {f.summary}"[:20] in " ".join(text.split())


def test_the_campaign_exports_every_registered_format():
    from hypothesis import HealthCheck, Phase, find, settings

    quick = settings(
        max_examples=2000,
        suppress_health_check=list(HealthCheck),
        database=None,
        phases=[Phase.generate],  # any example will do: no shrinking
    )
    for name in FORMATS:
        case = find(plans_strategy(), lambda c, name=name: c[1] == name, settings=quick)
        assert case[1] == name
    # and it has a content check for every kind of file a format writes
    for f in FORMATS.values():
        for s in f.suffixes:
            assert Path("x" + s.format(id=1)).suffix in OUTPUT_CHECKS, (f.name, s)


def test_every_format_writes_the_files_its_table_line_names(tmp_path):
    src = write_plan(sample_plan(), tmp_path / "mission.json")
    ids = [u["id"] for u in load_plan(src)["uavs"]]
    for name, f in FORMATS.items():
        out = tmp_path / name
        written = export_plan(src, name, ORIGIN, out)
        names = {p.name for p in written}
        assert names and names <= _file_names(f, "mission", ids), (name, names)
        assert {p.name for p in out.iterdir()} == names  # nothing else, nothing unlisted
        assert set(f.extras) <= set(metadata.metadata("poc-env").get_all("Provides-Extra") or [])


def test_a_new_format_is_one_table_line(tmp_path, monkeypatch, capsys):
    """export_plan and the CLI dispatch through the table: a line added is offered and used."""

    def write(job):
        return [job.path(".txt").write_text(json.dumps(len(job.plan["uavs"]))) and job.path(".txt")]

    monkeypatch.setitem(FORMATS, "count", Format("count", write, (".txt",), (), "UAV count"))
    src = write_plan(sample_plan(), tmp_path / "p.json")
    assert main(["export", str(src), "--format", "count", "--origin", ORIGIN]) == 0
    assert (tmp_path / "p.txt").read_text() == "2"
    assert main(["export", str(src), "--format", "nope", "--origin", ORIGIN]) == 2
    assert "count" in capsys.readouterr().err  # the error lists the table's names
