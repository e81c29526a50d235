"""`poc-env demo` (what `make demo` runs) produces every file it announces."""

from poc_env.cli import main


def test_demo_runs_end_to_end(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path), "--episodes", "1", "--workers", "1"]) == 0
    out = capsys.readouterr().out
    for needle in ("Table 4", "Table 6", "de_plan", "lawnmower", "physical optimum"):
        assert needle in out
    for name in (
        "survey.csv",
        "survey.png",
        "plan.json",
        "plan.png",
        "evaluate.csv",
        "posc_over_time.png",
    ):
        assert (tmp_path / name).stat().st_size > 0
