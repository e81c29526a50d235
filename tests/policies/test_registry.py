"""The policy registry: one place that names every policy, used by evaluate, render and the API."""

import numpy as np
import pytest

import poc_env.agents.policies.registry as registry
from poc_env.agents.experiments.evaluate import evaluate
from poc_env.agents.policies import Policy, make_policy, register, registered
from poc_env.cli import main
from poc_env.errors import ConfigError

BUILTIN = (
    "allocation_plan",
    "allocation_plan_standard",
    "allocation_plan_thorough",
    "de_plan",
    "de_receding",
    "greedy_bayes",
    "greedy_rectangles",
    "lawnmower",
    "potential_game",
    "random",
    "random_heading",
    "random_waypoint",
    "spacetime_plan",
    "spacetime_receding",
    "optimizer_plan:OPTIMIZER",
    "plan_choice:SPEC",
    "ppo:PATH",
    "receding_choice:SPEC",
    "rllib:PATH",
)


@pytest.fixture
def scratch_registry(monkeypatch):
    """A copy of the registry that the test may extend; the real one is left as it was."""
    monkeypatch.setattr(registry, "_REGISTRY", dict(registry._REGISTRY))


def test_every_builtin_policy_is_registered_and_made_fresh():
    assert registered() == BUILTIN
    for name in (n for n in BUILTIN if ":" not in n):
        a, b = make_policy(name), make_policy(name)
        assert isinstance(a, Policy) and a.name == name and a is not b
    factory = registry.spec("ppo:runs/x").load()  # imported by name: no RL import before this
    assert factory.__name__ == "PPOPolicy" and issubclass(factory, Policy)
    factory = registry.spec("rllib:runs/x").load()
    assert factory.__name__ == "RLlibPolicy" and issubclass(factory, Policy)


def test_keywords_reach_the_factory():
    pol = make_policy("de_plan", popsize=16, maxiter=20)
    assert (pol.popsize, pol.maxiter) == (16, 20)
    assert make_policy("potential_game", rounds=3).rounds == 3


def test_unknown_or_misspelt_names_list_the_registered_ones():
    for bad in ("telepathy", "ppo_v2", "lawnmower:x", "nope:x"):
        with pytest.raises(ConfigError, match="ppo:PATH") as err:
            make_policy(bad)
        assert err.value.field == "policy"
        assert all(name in err.value.allowed for name in BUILTIN)
    for bad in ("ppo", "ppo:"):
        with pytest.raises(ConfigError, match="checkpoint path"):
            make_policy(bad)


def test_register_checks_names_and_entry_points(scratch_registry):
    with pytest.raises(ConfigError, match="entry_point"):
        register("mower", "poc_env.agents.policies.lawnmower.LawnmowerPolicy")  # no ':'
    with pytest.raises(ConfigError, match="name"):
        register("a:b", "poc_env.agents.policies.lawnmower:LawnmowerPolicy")
    with pytest.raises(ConfigError, match="taken"):
        register("random", "poc_env.agents.policies.lawnmower:LawnmowerPolicy")
    register(
        "random", "poc_env.agents.policies.random:RandomPolicy"
    )  # the same entry again is fine
    register("ghost", "poc_env.agents.policies.no_such_module:Ghost")
    with pytest.raises(ConfigError, match="importable"):
        make_policy("ghost")
    register("not_a_policy", "numpy:zeros", kwargs={"shape": 2})
    with pytest.raises(ConfigError, match="Policy"):
        make_policy("not_a_policy")


def test_shipped_lists_each_policys_shipped_values_as_evaluate_spells_them(scratch_registry):
    """``shipped()`` (``poc-env policies``' list): each ``name:VALUE`` policy's shipped values,
    from the function its ``shipped`` entry names; a chooser model listed loads by its
    spelling. ``shipped`` is refused on a policy without an argument or when malformed."""
    from poc_env.agents.policies import plan_choice, replan_choice

    got = registry.shipped()
    for policy, names in (
        ("plan_choice", plan_choice.shipped_choosers()),
        ("receding_choice", replan_choice.shipped_choosers()),
    ):
        assert names and {f"{policy}:{n}" for n in names} <= set(got), (policy, got)
    for policy, module in (("plan_choice", plan_choice), ("receding_choice", replan_choice)):
        assert make_policy(f"{policy}:{module.shipped_choosers()[0]}").chooser == "model"
    register("listed", "poc_env.agents.policies.random:RandomPolicy", argument="seed",
             shipped="poc_env.agents.policies.plan_choice:shipped_choosers")  # fmt: skip
    assert {f"listed:{n}" for n in plan_choice.shipped_choosers()} <= set(registry.shipped())
    with pytest.raises(ConfigError, match=r"policies\[plain\]\.shipped"):
        register("plain", "poc_env.agents.policies.random:RandomPolicy",
                 shipped="poc_env.agents.policies.plan_choice:shipped_choosers")  # fmt: skip
    with pytest.raises(ConfigError, match=r"policies\[bad\]\.shipped"):
        register("bad", "poc_env.agents.policies.random:RandomPolicy", argument="seed",
                 shipped="no colon")  # fmt: skip


def test_a_registered_policy_flies_in_evaluate_with_its_defaults(scratch_registry):
    """A new name is all evaluate needs; registered keywords are the policy's defaults."""
    register("mower", "poc_env.agents.policies.lawnmower:LawnmowerPolicy")
    register("quick_game", "poc_env.agents.policies.game:PotentialGamePolicy", kwargs={"rounds": 2})
    assert "mower" in registered() and make_policy("quick_game").rounds == 2
    ev = evaluate("small", ["mower", "lawnmower"], episodes=1)
    mower, lawn = ev.episodes
    assert mower.posc_curve == lawn.posc_curve and mower.policy == "mower"


@pytest.mark.parametrize("name", ["greedy_bayes", "potential_game"])
def test_render_flies_any_registered_policy(tmp_path, name):
    out = tmp_path / f"{name}.gif"
    argv = ["render", "--policy", name, "--max-steps", "4", "--every", "2", "--out", str(out)]
    assert main(argv) == 0
    assert out.read_bytes()[:6] == b"GIF89a"


def test_render_gives_the_policy_the_observations_the_env_gives():
    """The render adapter's actions equal the policy's actions in the env, step by step."""
    from poc_env.cli import _state_policy
    from poc_env.config import load_scenario
    from poc_env.envs.parallel import UAVSearchParallelEnv

    sc = load_scenario("small")
    env = UAVSearchParallelEnv(sc)
    obs, _ = env.reset(seed=5)
    pol = make_policy("greedy_bayes")
    pol.reset(env, 5)
    fn = _state_policy(sc, "greedy_bayes", 5)
    rng = np.random.default_rng(0)
    for _ in range(8):
        acts, _ = pol.predict(obs)
        arr = fn(env.sim_state, rng)
        expected = np.array([acts[a] for a in env.possible_agents])
        np.testing.assert_array_equal(arr[0], expected)
        obs, *_ = env.step(acts)
