"""i24-flownsep: flown ``allocation_plan`` episodes (a script, not a test).

``python flown.py priors MAP SEED0 SEED1 OUT.jsonl``
    Per episode seed, the prior :func:`~poc_env.agents.experiments.evaluate.episode_prior`
    of that seed, flown with that seed.
``python flown.py case CASE N OUT.jsonl``
    ``mono2`` / ``lanes`` (results/plan_scale/i24-deconflict/repro.py's smoke cases at N UAVs)
    or a scenario file on its own prior at N UAVs (0: the file's fleet), flown with seed 5000.

Each flight's record: flown POSC (``repr``), collision UAV-steps (the environment's
``violation_collision``), those away from the fields (farther than ``d_s / sin FAN_DEG`` from
the UAV's take-off and landing fields), UAVs without a route and a sha256 of every step's
actions (equal digests: the same flight bit for bit). Records are appended to OUT.jsonl.
Run "before" from outside the checkout with ``PYTHONPATH=/path/to/main`` (the README).
"""

import hashlib
import json
import sys
from pathlib import Path

import numpy as np

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.agents.policies.registry import make_policy
from poc_env.config import load_scenario

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "i24-deconflict"))
from repro import case, flown_collisions


def flight(sc, seed: int, prior) -> dict:
    pol = make_policy("allocation_plan")
    h = hashlib.sha256()
    predict = pol.predict

    def logged(obs, *a, **k):
        act, st = predict(obs, *a, **k)
        for name in sorted(act):
            h.update(name.encode() + np.asarray(act[name], np.float32).tobytes())
        return act, st

    pol.predict = logged
    steps = flown_collisions(sc, prior, seed, pol)  # repro.py's count
    return {
        "seed": seed,
        "posc": repr(steps[2]),
        "collision_steps": steps[0],
        "away_from_fields": steps[1],
        "no_route": sum(1 for u in pol.plan["uavs"] if not u["waypoints_m"]),
        "actions_sha256": h.hexdigest()[:16],
    }


def main(argv: list[str]) -> None:
    import poc_env

    code = str(Path(poc_env.__file__).resolve().parents[1])
    with open(argv[-1], "a") as f:
        if argv[1] == "priors":
            sc = load_scenario(argv[2])
            for seed in range(int(argv[3]), int(argv[4])):
                rec = {"map": argv[2], **flight(sc, seed, episode_prior(sc, seed))}
                print(json.dumps({"code": code, **rec}), file=f, flush=True)
        else:
            name, n = argv[2], int(argv[3])
            if name in ("mono2", "lanes"):
                sc, prior = case(name, n)
            else:
                from poc_env.theory.probability_map import build_prior

                sc = load_scenario(name)
                sc = sc.with_uavs(n) if n else sc
                prior = build_prior(sc.map)
            rec = {"case": Path(name).name, "uavs": sc.n_uavs, **flight(sc, 5000, prior)}
            print(json.dumps({"code": code, **rec}), file=f, flush=True)


if __name__ == "__main__":
    main(sys.argv)
