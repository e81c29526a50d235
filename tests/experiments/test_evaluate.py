"""The evaluation harness: same seeds, same results, whatever the number of workers."""

import csv

import numpy as np
import pytest
import scipy.stats

from poc_env.agents.experiments.evaluate import effort_bound, evaluate
from poc_env.cli import main
from poc_env.errors import ConfigError


def test_identical_seeds_give_identical_results_and_workers_do_not_matter():
    a = evaluate("small", ["lawnmower", "random"], episodes=2)
    b = evaluate("small", ["lawnmower", "random"], episodes=2, workers=2)
    assert a.episodes == b.episodes
    rows = {r["policy"]: r for r in a.rows()}
    assert rows["lawnmower"]["posc_mean"] > rows["random"]["posc_mean"]
    assert all(e.posc <= a.bound + 1e-12 for e in a.episodes)


def test_bound_grows_with_the_fleet():
    from poc_env.config import load_scenario

    sc = load_scenario("small")
    assert effort_bound(sc.with_uavs(1)) < effort_bound(sc) <= 1.0


def test_bad_input():
    with pytest.raises(ConfigError, match="policies"):
        evaluate("small", ["telepathy"], episodes=1)
    with pytest.raises(ConfigError, match="episodes"):
        evaluate("small", ["random"], episodes=0)


def test_cli_evaluate(tmp_path, capsys):
    argv = [
        "evaluate",
        "--scenario",
        "small",
        "--policies",
        "lawnmower,random",
        "--episodes",
        "2",
        "--quiet",
        "--out",
        str(tmp_path),
    ]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "lawnmower" in out and "physical optimum" in out
    rows = list(csv.DictReader((tmp_path / "evaluate.csv").open()))
    assert [r["policy"] for r in rows] == ["lawnmower", "random"]
    eps = list(csv.DictReader((tmp_path / "episodes.csv").open()))
    assert len(eps) == 4 and {"normalised", "bound_reach"} <= set(eps[0])
    assert (tmp_path / "posc_over_time.png").read_bytes()[:4] == b"\x89PNG"
    assert main(["evaluate", "--scenario", "small", "--policies", "nope", "--quiet"]) == 2


def test_policies_come_from_the_registry():
    """evaluate makes its policies by name from poc_env.agents.policies.registry: an unknown name is
    refused before any episode runs, with every registered name in the message."""
    from poc_env.agents.policies.registry import registered

    with pytest.raises(ConfigError) as err:
        evaluate("small", ["lawnmower", "telepathy"], episodes=1)
    assert err.value.field == "policies" and err.value.value == "telepathy"
    assert err.value.allowed == "one of " + ", ".join(registered())
    with pytest.raises(ConfigError, match="checkpoint path"):
        evaluate("small", ["ppo:"], episodes=1)


def test_both_bounds_and_the_normalised_score(tmp_path):
    """Every episode carries the plain and the reach-aware bound of its prior; the normalised
    score is POSC / reach-aware bound, per episode and averaged in the rows and the CSV."""
    from poc_env.config import load_scenario
    from poc_env.theory.bound import honest_optimum, reach_bound
    from poc_env.theory.probability_map import build_prior

    ev = evaluate("small", ["lawnmower"], episodes=2)
    sc = load_scenario("small")
    prior = build_prior(sc.map)
    assert ev.bound == pytest.approx(honest_optimum(sc, prior).pos, abs=1e-12)
    assert ev.bound_reach == pytest.approx(reach_bound(sc, prior).upper, abs=1e-12)
    assert ev.bound_reach <= ev.bound + 1e-9
    for e in ev.episodes:
        assert e.bound == ev.bound and e.bound_reach == ev.bound_reach
        assert e.normalised == pytest.approx(e.posc / ev.bound_reach)
        assert e.posc <= e.bound_reach
    (row,) = ev.rows()
    assert row["normalised"] == pytest.approx(row["posc_mean"] / ev.bound_reach)
    assert "POSC/reach" in ev.table() and "reach-aware bound" in ev.table()
    rows = list(csv.DictReader(ev.to_csv().splitlines()))
    assert float(rows[0]["bound_reach"]) == pytest.approx(ev.bound_reach)
    assert float(rows[0]["normalised"]) == pytest.approx(row["normalised"])
    per_episode = list(csv.DictReader(ev.episodes_csv().splitlines()))
    assert [int(r["seed"]) for r in per_episode] == [e.seed for e in ev.episodes]
    for r, e in zip(per_episode, ev.episodes, strict=True):
        assert float(r["normalised"]) == pytest.approx(e.posc / ev.bound_reach)
    # random priors: each episode's own bounds, the mean in the table
    rp = evaluate("small", ["lawnmower"], episodes=2, random_priors=True)
    reach = [e.bound_reach for e in rp.episodes]
    assert reach[0] != reach[1] and rp.bound_reach == pytest.approx(np.mean(reach))
    assert rp.rows()[0]["normalised"] == pytest.approx(
        np.mean([e.posc / e.bound_reach for e in rp.episodes])
    )
    assert all(e.posc <= e.bound_reach <= e.bound + 1e-9 for e in rp.episodes)
    rows = rp.episode_rows()
    assert [r["bound_reach"] for r in rows] == reach
    assert [r["normalised"] for r in rows] == [e.posc / e.bound_reach for e in rp.episodes]


def test_paired_differences_against_a_baseline(tmp_path, capsys):
    """``--baseline``: per-seed differences on shared seeds, read back from paired.csv and
    recomputed from episodes.csv; a baseline outside --policies is refused before any run."""
    out = tmp_path / "ev"
    argv = ["evaluate", "--scenario", "small", "--policies", "lawnmower,random,greedy_bayes"]
    argv += ["--episodes", "3", "--random-priors", "--quiet", "--baseline", "random,lawnmower"]
    assert main([*argv, "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "paired differences in POSC against random" in text
    assert "paired differences in POSC against lawnmower" in text
    eps = list(csv.DictReader((out / "episodes.csv").open()))
    posc = {(e["policy"], int(e["seed"])): float(e["posc"]) for e in eps}
    paired = list(csv.DictReader((out / "paired.csv").open()))
    assert {(r["baseline"], r["policy"]) for r in paired} == {
        ("random", "lawnmower"), ("random", "greedy_bayes"),
        ("lawnmower", "random"), ("lawnmower", "greedy_bayes"),
    }  # fmt: skip
    for r in paired:
        p, b = r["policy"], r["baseline"]
        d = np.array([posc[p, s] - posc[b, s] for s in (1000, 1001, 1002)])
        assert float(r["diff_mean"]) == pytest.approx(d.mean(), abs=1e-12)
        t = scipy.stats.t.ppf(0.975, 2)  # Student's t, 2 degrees of freedom (4.30, not 1.96)
        assert float(r["diff_ci95"]) == pytest.approx(t * d.std(ddof=1) / np.sqrt(3))
        assert int(r["wins"]) + int(r["ties"]) + int(r["losses"]) == 3
        assert int(r["wins"]) == int((d > 1e-12).sum())
    bad = ["evaluate", "--scenario", "small", "--policies", "lawnmower", "--baseline", "random"]
    assert main([*bad, "--quiet", "--out", str(tmp_path / "none")]) == 2
    assert "baseline" in capsys.readouterr().err
    assert not (tmp_path / "none").exists()


def test_a_lone_baseline_is_refused_before_anything_flies(tmp_path, capsys):
    """``--baseline X`` with X the only policy flew every episode and then failed writing an
    empty paired table (IndexError, nothing written); it is refused up front, by evaluate and by
    summarise on a folder of one policy."""
    out = tmp_path / "ev"
    lone = ["evaluate", "--scenario", "small", "--policies", "lawnmower", "--episodes", "1",
            "--quiet", "--out", str(out)]  # fmt: skip
    assert main([*lone, "--baseline", "lawnmower"]) == 2
    assert "baseline: got 'lawnmower'" in capsys.readouterr().err
    assert not out.exists()
    assert main(lone) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert main(["summarise", str(out), "--baseline", "lawnmower"]) == 2
    assert "at least one other policy" in capsys.readouterr().err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


@pytest.mark.parametrize("priors", [[], ["--random-priors"]])
def test_summarise_rewrites_the_summary_evaluate_wrote_from_episodes_csv(tmp_path, capsys, priors):
    """``poc-env summarise`` (issue 27): the summary files from episodes.csv alone equal the
    ones ``evaluate`` wrote (the paired tables of its baselines included); in place, the other
    files of the folder are left as they were."""
    out = tmp_path / "ev"
    argv = ["evaluate", "--scenario", "small", "--policies", "lawnmower,random", "--episodes",
            "3", "--quiet", "--baseline", "random", "--out", str(out), *priors]  # fmt: skip
    assert main(argv) == 0
    names = ("evaluate.csv", "evaluate.txt", "paired.csv")
    wrote = {n: (out / n).read_bytes() for n in names}
    again = tmp_path / "again"
    assert main(["summarise", str(out), "--out", str(again)]) == 0
    assert {n: (again / n).read_bytes() for n in names} == wrote
    assert sorted(p.name for p in again.iterdir()) == sorted(names)
    for n in ("evaluate.csv", "evaluate.txt"):  # in place: the same bytes again (paired.csv
        (out / n).write_text("stale")  # names the baselines), episodes.csv untouched
    episodes = (out / "episodes.csv").read_bytes()
    assert main(["summarise", str(out)]) == 0
    assert {n: (out / n).read_bytes() for n in names} == wrote
    assert (out / "episodes.csv").read_bytes() == episodes
    assert "±95%" in capsys.readouterr().out


def test_summarise_refuses_a_bad_episodes_csv_and_writes_nothing(tmp_path, capsys):
    folder = tmp_path / "ev"
    folder.mkdir()
    good = "policy,seed,posc,bound,bound_reach,normalised,detected,violation_steps,crashed,landed"
    cases = {
        "no file": None,
        "a column short": good.rsplit(",", 1)[0] + "\nrandom,1,0.1,0.9,0.8,0.1,True,0,0\n",
        "NaN": good + "\nrandom,1,nan,0.9,0.8,0.1,True,0,0,3\n",
        "text": good + "\nrandom,1,0.1,0.9,0.8,0.1,maybe,0,0,3\n",
        "seeds": good + "\na,1,0.1,0.9,0.8,0.1,True,0,0,3\nb,2,0.1,0.9,0.8,0.1,True,0,0,3\n",
        "binary": "\udcff\x00",
    }
    for name, text in cases.items():
        if text is not None:
            (folder / "episodes.csv").write_bytes(text.encode("utf-8", "surrogateescape"))
        assert main(["summarise", str(folder)]) == 2, name
        err = capsys.readouterr().err
        assert "error: " in err and "allowed: " in err, (name, err)
        assert sorted(p.name for p in folder.iterdir()) == ([] if text is None else
                                                            ["episodes.csv"]), name  # fmt: skip


def test_a_task_flown_with_overrides_is_not_printed_as_the_task(capsys):
    """Audit (i28-audit): ``evaluate --task ID --overrides ...`` printed its scores under the
    bare id, though the overrides make another MDP (scores compare only between equal ids)."""
    argv = ["evaluate", "--task", "UAVSearch-Small-Heading-v1", "--policies", "random"]
    argv += ["--episodes", "1", "--quiet"]
    assert main([*argv, "--overrides", "episode.horizon_steps=3"]) == 0
    head = capsys.readouterr().out.splitlines()[0]
    assert head.startswith("poc_env/UAVSearch-Small-Heading-v1 with --overrides ")
    assert "episode.horizon_steps=3 (not the registered task)" in head
    assert main(argv) == 0
    assert (
        capsys.readouterr()
        .out.splitlines()[0]
        .startswith("poc_env/UAVSearch-Small-Heading-v1: 1 episodes")
    )


def test_a_repeated_policy_is_refused_before_any_episode():
    """Audit (i28-audit): a policy named twice flew twice and its two runs were pooled into
    one row over twice the episodes (``bench baselines --episodes 1 --policies a,a`` printed
    "over 2 seeds" and an interval over copies)."""
    with pytest.raises(ConfigError, match=r"^policies: .*each policy once \(repeated: random\)"):
        evaluate("small", ["random", "lawnmower", "random"], episodes=1)


def test_one_episode_prints_no_interval():
    """With one episode there is no spread to estimate: the tables print ``-`` in the ±95 %
    column (they printed 0.0000, which reads as certainty); two episodes print the number."""
    one = evaluate("small", ["lawnmower", "random"], episodes=1)
    row = one.table().splitlines()[2].split()
    assert row[0] == "lawnmower" and row[2] == "-"
    assert one.paired_table("random").splitlines()[3].split()[2] == "-"
    two = evaluate("small", ["lawnmower", "random"], episodes=2)
    assert two.table().splitlines()[2].split()[2] == f"{two.rows()[0]['posc_ci95']:.4f}"


def test_a_folder_evaluated_again_without_baseline_keeps_no_old_pairings(tmp_path, capsys):
    """Audit (exp-audit, noticed): a second ``evaluate --out DIR`` without ``--baseline`` left
    the first run's paired.csv beside the new episodes, and ``summarise`` then paired them
    against that old baseline. paired.csv is now always written (its header alone)."""
    from poc_env.agents.experiments.evaluate import PAIRED_COLUMNS

    out = tmp_path / "ev"
    argv = ["evaluate", "--scenario", "small", "--episodes", "2", "--quiet", "--out", str(out)]
    assert main([*argv, "--policies", "lawnmower,random", "--baseline", "random"]) == 0
    assert "random" in (out / "paired.csv").read_text()
    assert main([*argv, "--policies", "lawnmower,greedy_bayes"]) == 0
    rows = list(csv.DictReader((out / "paired.csv").open()))
    assert rows == [] and (out / "paired.csv").read_bytes().decode().split("\r\n")[0] == ",".join(
        PAIRED_COLUMNS
    )
    capsys.readouterr()
    assert main(["summarise", str(out)]) == 0
    assert "paired differences" not in capsys.readouterr().out
