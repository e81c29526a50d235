"""Ship a chooser model: its file with the card's evaluation in ``meta["evaluation"]`` (the
fields of :func:`poc_env.agents.rl.card.make_card`'s ``evaluation``), written to
``agents/checkpoints/choosers/NAME.json``.

    PYTHONPATH=. python results/drift_replan/card.py runs/drift_replan/chooser.json \
        --evaluation results/drift_replan/evaluation --policy receding_choice:PATH \
        --name receding_chooser_drift_small
"""

from __future__ import annotations

import argparse
from pathlib import Path

from poc_env.agents.policies.replan_choice import ChooserModel
from poc_env.agents.rl.card import make_card

ROOT = Path(__file__).resolve().parents[2]
TASK = "UAVSearch-Small-Drift-Heading-v1"


def replay(path: Path, model: ChooserModel, seeds: list[int]) -> dict:
    """The first evaluation episode in which the model's own decision is not ``keep`` (so a
    replay checks the model, not only the rule): its seed, POSC and picks."""
    from poc_env.agents.policies.replan_choice import ReplanChoicePolicy
    from poc_env.envs.parallel import UAVSearchParallelEnv
    from poc_env.tasks import get_task

    sc = get_task(TASK).load_scenario({})
    decide = tuple(model.meta["decide_min"])
    for seed in seeds:
        pol = ReplanChoicePolicy("model", str(path), decide)
        env = UAVSearchParallelEnv(scenario=sc)
        obs, _ = env.reset(seed=seed)
        pol.reset(env, seed)
        while env.agents:
            obs, *_ = env.step(pol.predict(obs)[0])
        mine = [d for d in pol.decisions if any(abs(d["time_s"] - t) < 1e-6 for t in pol.model_s)]
        if any(d["pick"] != 0 for d in mine):
            picks = [d["names"][d["pick"]] for d in pol.decisions]
            return {"seed": seed, "posc": float(env.sim_state.posc[0]), "picks": picks}
    raise SystemExit("the model keeps the routes in every evaluation episode")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("model", type=Path)
    ap.add_argument("--evaluation", type=Path, required=True)
    ap.add_argument("--policy", required=True, help="the model's row in the evaluation")
    ap.add_argument("--name", required=True)
    args = ap.parse_args()
    model = ChooserModel.load(args.model)
    card = make_card(args.model, None, args.evaluation, args.policy, recipe="replan_chooser")
    model.meta["task"] = TASK
    model.meta["evaluation"] = card["evaluation"]
    model.meta["replay"] = replay(args.model, model, card["evaluation"]["seeds"])
    out = ROOT / "agents" / "checkpoints" / "choosers" / f"{args.name}.json"
    print(f"wrote {model.save(out)}")


if __name__ == "__main__":
    main()
