"""The single environment's fast step (poc_env.sim.single, poc_env._kernels.swarm) against the
engine's numpy step, bit for bit.

The PettingZoo env steps through :class:`~poc_env.sim.single.SingleStep` (the engine's step with
the reward terms, the episode end and the info values in one compiled call); a second env of
the same arguments with the fast step switched off (``_single = None``: the engine's
:meth:`~poc_env.sim.engine.Engine.step`, :mod:`~poc_env.sim.rewards` and
:func:`~poc_env.sim.engine.info_parts`) runs the same seeded random episode, and every
observation, reward, termination, truncation, info (keys, order, Python types, values) and the
transition arrays must be identical: equal floats, not close ones.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import poc_env
from poc_env import spec
from poc_env._kernels import swarm as kernel
from poc_env.config import load_scenario
from poc_env.sim import core as sim
from poc_env.sim import engine as engine_mod
from poc_env.sim import rewards, single

NOFLY = {"map.no_fly_zones_km": [[[24, 15], [30, 15], [30, 25], [24, 25]]]}
THREAT = {"map.threat_peaks": [{"center_km": [8, 8], "lambda_per_km2": 0.05}]}
#: (scenario, env keyword arguments): violations, terminations, credits, controls, priors, drift.
CASES = [
    ("paper_6_2", {"max_cycles": 30}),
    ("small", {"random_prior": True, "obs_type": "flat"}),
    ("small", {"overrides": {**NOFLY, **THREAT, "constraints.violation": "terminate"}}),
    (
        "small",
        {
            "overrides": {
                "constraints.safety_distance_km": 3,
                "comms.range_km": 12,
                "comms.min_neighbours": 3,
                "reward.credit": "individual",
                "reward.beta": 0.5,
                "reward.alpha": 2,
                "episode.detection_ends_episode": True,
                "sensor.sweep_width_km": 8,
            }
        },
    ),
    ("small", {"overrides": {"comms.link_failure_prob": 0.3}, "max_cycles": 12}),
    ("small", {"control": "heading", "obs_type": "compass", "random_airfields": True}),
    ("small", {"control": "waypoint", "target__model": "drift", "target__random_current_kmh": 25}),
    # a current that carries the hidden target out of the map within the episode
    ("small", {"target__model": "drift", "target__random_current_kmh": 100}),
    ("small", {"overrides": {"fleet": [{"takeoff": "A", "count": 9}], "reward.beta": 1}}),
    # the shield: the engine's core step, then the end-of-step kernel alone
    ("small", {"overrides": {**NOFLY, "constraints.violation": "shield"}, "max_cycles": 40}),
    # a map whose origin is not 0: the sweep's grid-relative legs
    ("small", {"overrides": {"map.origin_km": [0.437, -0.291]}, "obs_type": "flat"}),
]


def _same(a, b, path="") -> None:
    """``a`` and ``b`` identical: the same types, keys in the same order, equal values (arrays:
    same dtype, shape and elements, NaN equal to NaN)."""
    assert type(a) is type(b), f"{path}: {type(a)} != {type(b)}"
    if isinstance(a, dict):
        assert list(a) == list(b), f"{path}: keys {list(a)} != {list(b)}"
        for k in a:
            _same(a[k], b[k], f"{path}[{k}]")
    elif dataclasses.is_dataclass(a):
        for f in dataclasses.fields(a):
            _same(getattr(a, f.name), getattr(b, f.name), f"{path}.{f.name}")
    elif isinstance(a, tuple | list):
        assert len(a) == len(b), f"{path}: {len(a)} != {len(b)}"
        for k, (x, y) in enumerate(zip(a, b, strict=True)):
            _same(x, y, f"{path}[{k}]")
    elif isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and a.shape == b.shape, f"{path}: {a.dtype}{a.shape}"
        assert np.array_equal(a, b, equal_nan=a.dtype.kind == "f"), f"{path}: {a} != {b}"
    elif isinstance(a, float):
        assert a == b or (a != a and b != b), f"{path}: {a!r} != {b!r}"
    else:
        assert a == b, f"{path}: {a!r} != {b!r}"


def _pair(name: str, kwargs: dict):
    fast = poc_env.parallel_env(name, **kwargs)
    ref = poc_env.parallel_env(name, **kwargs)
    assert fast._single is not None, "the fast step is not used"
    ref._single = None
    return fast, ref


@pytest.mark.parametrize(("name", "kwargs"), CASES, ids=[str(i) for i in range(len(CASES))])
def test_fast_step_equals_the_engines_step(name, kwargs):
    fast, ref = _pair(name, kwargs)
    rng = np.random.default_rng(7)
    steps = 0
    for episode in range(3):
        got, want = fast.reset(seed=episode), ref.reset(seed=episode)
        _same(got, want, "reset")
        for st in (fast.sim_state, ref.sim_state):  # over the area: sensing, landings, violations
            rs = np.random.default_rng(episode)
            x0, y0, x1, y1 = fast.params.grid.bounds
            st.pos[..., 0] = rs.uniform(x0, x1, st.pos.shape[:2])
            st.pos[..., 1] = rs.uniform(y0, y1, st.pos.shape[:2])
            st.left_home[:] = rs.random(st.left_home.shape) < 0.5
        stop = steps + 25
        while fast.agents and steps < stop:
            dim = fast.action_space(fast.agents[0]).shape[0]
            acts = {a: rng.uniform(-1.2, 1.2, dim) for a in fast.agents}
            got, want = fast.step(acts), ref.step(acts)
            _same(got, want, f"step {steps}")
            # the state too: the hidden target's exponent shows in no output until detection
            _same(fast.sim_state, ref.sim_state, f"state at step {steps}")
            assert fast.agents == ref.agents
            if steps % 7 == 0:  # the arrays behind the dicts, made when asked for
                tf, tr = fast.transition, ref.transition
                fields = ("reward", "terms", "events", "terminated", "truncated", "over", "info")
                for field in fields:
                    _same(getattr(tf, field), getattr(tr, field), field)
                _same(fast.info_arrays, ref.info_arrays, "info_arrays")
            steps += 1
    assert steps >= 15


def test_fast_step_covers_terminations_truncations_and_violations():
    """The cases above reach what the kernel computes: violations, crashes, landings or
    detections, truncations (so a test of them is not vacuous)."""
    seen: dict[str, bool] = {}
    for name, kwargs in CASES[2:5]:
        env = poc_env.parallel_env(name, **kwargs)
        rng = np.random.default_rng(7)
        env.reset(seed=0)
        while env.agents:
            acts = {a: rng.uniform(-1.2, 1.2, 3) for a in env.agents}
            _, _, term, trunc, infos = env.step(acts)
            seen["terminated"] = seen.get("terminated", False) or any(term.values())
            seen["truncated"] = seen.get("truncated", False) or any(trunc.values())
            for info in infos.values():
                seen["violation"] = seen.get("violation", False) or info["reward_violation"] < 0
                seen["crash"] = seen.get("crash", False) or info["reward_crash"] < 0
                seen["time"] = seen.get("time", False) or info["reward_time"] < 0
    assert all(seen.values()) and len(seen) == 5, seen


def test_numpy_sum_is_numpys_pairwise_sum():
    """:func:`~poc_env._kernels.swarm.numpy_sum` gives ``ndarray.sum``'s bits at every size
    (the plain, eight-accumulator and halving branches), values of mixed magnitudes, -0.0."""
    rng = np.random.default_rng(0)
    for n in [*range(0, 40), 127, 128, 129, 255, 256, 300, 1000]:
        for _ in range(5):
            x = rng.standard_normal(n) * 10.0 ** rng.integers(-12, 12, n)
            assert kernel.numpy_sum(x) == x.sum(), n
            assert kernel.numpy_sum(x[None][0]) == x[None].sum(axis=1)[0]
        z = np.full(n, -0.0)
        assert np.signbit(kernel.numpy_sum(z)) == np.signbit(z.sum()), n


def _random_events(rng, e, n):
    flag = lambda: rng.random((e, n)) < 0.3  # noqa: E731
    return sim.Events(
        pos_agent=rng.random((e, n)) * 10.0 ** rng.integers(-9, 0, (e, n)),
        pos_team=rng.random(e),
        time_term=np.where(flag(), 0.0, rng.random((e, n)) * 1e-2),
        overtime=flag(),
        out_of_bounds=flag(),
        no_fly=flag(),
        collision=flag(),
        threat=flag(),
        comms_ok=~flag(),
        shielded=flag(),
        landed_now=flag(),
        crashed_now=flag(),
        detected_now=rng.random(e) < 0.5,
        connected=rng.random(e) < 0.5,
    )


@pytest.mark.parametrize("credit", ["team", "individual"])
@pytest.mark.parametrize("ends", [False, True])
def test_end_step_kernel_equals_the_numpy_rules(credit, ends):
    """The kernel against :func:`rewards.reward_terms`, :func:`rewards.total_reward`,
    :func:`core.terminal`, :func:`core.truncated`, :func:`core.episode_over` and
    :func:`engine.info_parts` on random events and states, batched, with float and int
    coefficients, many sizes (the team time term's sum in numpy's order)."""
    rng = np.random.default_rng(3)
    for k in range(30):
        e, n = int(rng.integers(1, 4)), int(rng.integers(1, 20))
        over = {
            "reward.credit": credit,
            "reward.alpha": [1, 0.7, 3][k % 3],
            "reward.beta": [0, 0.0, 0.25][k % 3],
            "reward.crash_penalty": [0.1, 1, 0.0][k % 3],
            "episode.detection_ends_episode": ends,
            "fleet": [{"takeoff": "A", "count": n}],
        }
        sc = load_scenario("small", over)
        p = sim.make_params(sc)
        state = sim.initial(p, [np.random.default_rng(k + i) for i in range(e)])
        state.landed[:] = rng.random((e, n)) < 0.2
        state.crashed[:] = rng.random((e, n)) < 0.2
        state.detected[:] = rng.random(e) < 0.5
        state.detect_step[:] = np.where(state.detected, rng.integers(1, 50, e), -1)
        state.step[:] = rng.integers(p.horizon - 2, p.horizon + 2, e)
        state.elapsed[:] = rng.random((e, n)) * 1e4
        state.posc[:] = rng.random(e)
        state.violations[:] = rng.integers(0, 9, (e, n))
        ev = _random_events(rng, e, n)
        eng = engine_mod.Engine(sc, e)
        step = single.SingleStep(eng)
        terms = np.empty((5, e, n))
        reward = np.empty((e, n))
        term, trunc = np.empty((e, n), bool), np.empty((e, n), bool)
        done = np.empty(e, bool)
        fi = np.empty((e, n, len(kernel.FLOAT_INFOS)))
        bi = np.empty((e, n, len(kernel.BOOL_INFOS)), bool)
        ii = np.empty((e, n, len(kernel.INT_INFOS)), np.int64)
        parts = single.parts_of(ev)
        _same(single.events_of(parts), ev, "events")
        kernel.end_step(
            parts,
            (state.posc, state.elapsed, state.detected, state.detect_step, state.topology,
             state.violations, state.landed, state.crashed, state.step),
            step._coefficients(p.dt), p.horizon, ends, credit == "team",
            (terms, reward, term, trunc, done, fi, bi, ii),
        )  # fmt: skip
        want_terms = rewards.reward_terms(sc.reward, ev)
        assert tuple(want_terms) == single.TERMS == spec.names(spec.REWARD_TERMS)
        for j, t in enumerate(single.TERMS):
            _same(terms[j], want_terms[t], t)
            assert (np.signbit(terms[j]) == np.signbit(want_terms[t])).all(), t
        _same(reward, rewards.total_reward(want_terms), "reward")
        _same(term, sim.terminal(p, state), "terminated")
        _same(trunc, sim.truncated(p, state), "truncated")
        _same(done, sim.episode_over(p, state), "over")
        parts = engine_mod.info_parts(p, state, ev, want_terms)
        for group, arr in (
            (kernel.FLOAT_INFOS, fi),
            (kernel.BOOL_INFOS, bi),
            (kernel.INT_INFOS, ii),
        ):
            for j, key in enumerate(group):
                want = parts[key]
                want = np.repeat(want[:, None], n, axis=1) if want.ndim == 1 else want
                _same(arr[..., j], want.astype(arr.dtype), key)
                assert want.dtype.kind == arr.dtype.kind, key


@pytest.mark.parametrize(
    "overrides",
    [
        {"target.model": "drift", "target.random_current_kmh": 25},  # a target off the map
        {"sensor.law": "definite_range", "sensor.samples_per_cell": 1},  # a POD of 1: log1p(-1)
        {**NOFLY, **THREAT, "comms.topology": "table2", "fleet": [{"takeoff": "A", "count": 5}]},
    ],
    ids=["target-out", "pod-1", "zones-table2"],
)
def test_core_step_equals_sim_step_on_crafted_states(overrides):
    """The single step's core (:meth:`SingleStep._core_step`) against :func:`core.step` on
    states the random episodes rarely reach: a UAV flying over a hidden target that has left
    the map, a detection probability of exactly 1, no-fly zones, threats and Table 2."""
    import copy

    sc = load_scenario("small", overrides)
    eng = engine_mod.Engine(sc, 1, seeds=[0])
    eng.reset()
    st = eng.current
    rng = np.random.default_rng(1)
    x0, y0, x1, y1 = eng.params.grid.bounds
    st.pos[0, :, 0] = rng.uniform(x0, x1, st.pos.shape[1])
    st.pos[0, :, 1] = rng.uniform(y0, y1, st.pos.shape[1])
    st.pos[0, 0, :2] = st.target[0]  # UAV 0 sweeps the target
    if st.target_out is not None:
        st.target_out[:] = True
    fast_step = single.SingleStep(eng)
    for _ in range(3):
        acts = rng.uniform(-1, 1, (1, st.flying.shape[1], 3))
        want_state, got_state = copy.deepcopy(st), copy.deepcopy(st)
        want = sim.step(eng.params, want_state, acts, [np.random.default_rng(5)])
        eng.rngs = [np.random.default_rng(5)]
        k = fast_step._constants(eng.params)
        e, n = st.flying.shape
        parts = fast_step._core_step(
            eng.params, k, got_state, acts.astype(float), fast_step.scratch(e, n)
        )
        _same(single.events_of(parts), want, "events")
        _same(got_state, want_state, "state")
        st = eng.state = got_state


def test_returned_values_are_not_changed_by_later_steps():
    """What a step returns (observations, infos with their adjacency rows, the transition's
    arrays) stays as it was when the env steps on: the fast step reuses only scratch arrays
    that never leave it."""
    import copy

    env = poc_env.parallel_env("small", overrides={"comms.range_km": 12})
    env.reset(seed=3)
    rng = np.random.default_rng(3)
    kept = []
    while env.agents and len(kept) < 8:
        out = env.step({a: rng.uniform(-1, 1, 3) for a in env.agents})
        tr = env.transition
        arrays = (tr.reward, tr.terms, tr.terminated, tr.truncated, tr.over, tr.events)
        kept.append(((out, arrays), copy.deepcopy((out, arrays))))
    assert len(kept) == 8
    for got, want in kept:
        _same(got, want, "kept")


@pytest.mark.parametrize("law", ["inverse_cube", "exponential", "definite_range"])
def test_fused_kernels_equal_the_kernels_they_join(law):
    """The single step's fused calls against what they replace, on random states of many
    sizes: ``sensing.sense_step`` against :func:`core.sense` (numpy's origin shifts, the sweep)
    and the hidden target kernel as :func:`core.step` calls it; ``sensing.fly_sense`` against
    :func:`core.kinematics`, then ``sense_step``; ``swarm.step_end`` against the
    bookkeeping kernel, the auto topology and the end-of-step kernel called one by one;
    ``observations.vectors_of`` against ``vectors``; ``swarm.all_finite`` against numpy."""
    import copy

    from poc_env._kernels import observations as obs_kernels
    from poc_env._kernels import sensing
    from poc_env.sim import observations as obs_mod

    rng = np.random.default_rng(11)
    for k in range(8):
        e, n = int(rng.integers(1, 4)), int(rng.integers(1, 13))
        sc = load_scenario(
            "small",
            {
                "sensor.law": law,
                "fleet": [{"takeoff": "A", "count": n}],
                "comms.range_km": float(rng.uniform(5, 40)),
                "reward.credit": ["team", "individual"][k % 2],
                "episode.detection_ends_episode": bool(k % 3 == 0),
                "map.origin_km": [0.0, 0.0] if k == 0 else rng.uniform(-0.9, 0.9, 2).tolist(),
            },
        )
        p = sim.make_params(sc)
        st = sim.initial(p, [np.random.default_rng(k + i) for i in range(e)])
        x0, y0, x1, y1 = p.grid.bounds
        old = st.pos.copy()
        old[..., 0] = rng.uniform(x0 - 2e3, x1 + 2e3, (e, n))
        old[..., 1] = rng.uniform(y0 - 2e3, y1 + 2e3, (e, n))
        new = old.copy()
        new[..., :2] += rng.normal(0.0, 3e3, (e, n, 2))
        new[:, 0, :2] = old[:, 0, :2]  # a zero-length step
        st.target[:, :2] = new[:, -1, :2]  # a UAV right over its env's target
        moving = rng.random((e, n)) < 0.8
        steps = single.SingleStep(engine_mod.Engine(sc, e))
        kc = single._Constants(p)

        # sensing: the fused call against core.sense and the target kernel as core.step calls it
        got_st, want_st = copy.deepcopy(st), copy.deepcopy(st)
        found, p_t = np.empty((e, n)), np.empty((e, n))
        hit = sensing.sense_step(got_st.belief, old, new, moving, st.target, *kc.sense, found, p_t)
        want_found = sim.sense(p, want_st, old[..., :2].copy(), new[..., :2])
        want_p = np.empty((e, n))
        ox, oy = p.grid.origin_m
        want_hit = sensing.target_pod(
            st.target, old[..., :2].copy(), new[..., :2], moving, float(ox), float(oy),
            sensing.LAW_CODES[law], float(sc.sensor.sweep_width_m), float(p.cutoff_m),
            float(p.grid.cell_m), want_p,
        )  # fmt: skip
        _same(found, want_found, "found")
        _same(got_st.belief, want_st.belief, "belief")
        _same(p_t, want_p, "p_t")
        code = 0 if not want_p.any() else 2 if (want_p >= 1).any() | np.isnan(want_p).any() else 1
        assert hit == code and bool(hit) == want_hit

        # the kinematics and the sensing in one call against sim.kinematics, then sense_step
        acts = rng.uniform(-1.2, 1.2, (e, n, 3))
        fly_st, ref_st = copy.deepcopy(st), copy.deepcopy(st)
        ref_new = sim.kinematics(p, ref_st, acts, moving)
        ref_found, ref_p = np.empty((e, n)), np.empty((e, n))
        ref_hit = sensing.sense_step(
            ref_st.belief, st.pos, ref_new, moving, st.target, *kc.sense, ref_found, ref_p
        )
        fly = [np.empty_like(st.pos), *np.empty((3, e, n))]
        fly_found, fly_p = np.empty((e, n)), np.empty((e, n))
        fly_hit = sensing.fly_sense(
            acts, moving, st.pos, st.heading, st.pitch, st.speed, p.motion_constants, *fly,
            fly_st.belief, st.target, *kc.sense, fly_found, fly_p,
        )  # fmt: skip
        _same(fly, [ref_new, ref_st.heading, ref_st.pitch, ref_st.speed], "kinematics")
        _same((fly_found, fly_p, fly_st.belief), (ref_found, ref_p, ref_st.belief), "fly_sense")
        assert fly_hit == ref_hit

        # the bookkeeping, topology and end of step: one call against three
        st.step[:] = rng.integers(p.horizon - 2, p.horizon + 1, e)
        st.elapsed[:] = rng.random((e, n)) * sc.uav.endurance_s
        st.target_exponent[:] = rng.random(e) * 3
        nofly, threat, shielded = rng.random((3, e, n)) < 0.2
        coef = steps._coefficients(p.dt)
        ends_on, team = bool(sc.episode.detection_ends_episode), sc.reward.credit == "team"
        # the hidden target's miss, some PODs 0 (and, with k odd, every one: no hit)
        p_miss = np.where(rng.random((e, n)) < 0.5, 0.0, rng.random((e, n)) ** 4)
        with np.errstate(divide="ignore"):
            log_miss = np.log1p(-p_miss)
        hit_code = k % 2
        runs = []
        for fused in (True, False):
            s = copy.deepcopy(st)
            s.pos = new.copy()
            out = single._Scratch(e, n)
            for arr in vars(out).values():  # what neither writes compares equal
                if isinstance(arr, np.ndarray):
                    arr[...] = 0
            links = np.empty((e, n, n), dtype=bool)
            # the sensed arrays as the fused call takes them: rows of the scratch
            out.found[...], out.log_miss[...] = found, log_miss
            for row, flag in zip(out.airspace, (nofly, threat, shielded), strict=True):
                row[...] = flag
            state = (
                s.agent_pos, s.posc, s.pos, s.speed, s.target_exponent, s.target_threshold,
                s.step, s.detected, s.detect_step, s.elapsed, s.left_home, s.landed,
                s.crashed, s.flying, s.violations,
            )  # fmt: skip
            events = (out.team, out.detected_now, out.time_term, out.flags, out.dist)
            parts = (
                out.found, out.team, out.time_term, out.flags, *out.airspace, out.detected_now,
                out.connected,
            )  # fmt: skip
            if fused:
                kernel.step_end(
                    *state, s.topology, moving, hit_code, out.team, out.dist, links, out.rows_f,
                    out.rows_b, out.rows_e, p.landing, p.step_constants, kc.range_m,
                    kc.k_nearest, coef, p.horizon, ends_on, team, out.finfo, out.binfo,
                    out.iinfo,
                )  # fmt: skip
            else:
                if hit_code:  # as core.step adds it
                    s.target_exponent += -np.log1p(-p_miss).sum(axis=1)
                kernel.step(state, (out.found, moving, *out.airspace[:2]), events, p.landing,
                            p.step_constants)  # fmt: skip
                n_comp = np.empty(e, dtype=np.int64)
                kernel.auto_links(out.dist, kc.range_m, s.flying, kc.k_nearest, links, n_comp)
                out.connected[:] = n_comp <= 1
                kernel.end_step(
                    parts,
                    (s.posc, s.elapsed, s.detected, s.detect_step, s.topology, s.violations,
                     s.landed, s.crashed, s.step),
                    coef, p.horizon, ends_on, team,
                    (out.values[:5], out.values[5], out.ends[0], out.ends[1], out.over,
                     out.finfo, out.binfo, out.iinfo),
                )  # fmt: skip
            runs.append((s, links, parts, vars(out)))
        _same(runs[0], runs[1], "step_end")

        # the vector observation with its scalars in one array
        vec = np.empty((2, e, n, obs_mod.VECTOR_SIZE), dtype=np.float32)
        args = (st.pos, st.speed, np.sin(st.heading), np.cos(st.heading), st.pitch, st.elapsed,
                st.flying, st.step, p.landing)  # fmt: skip
        c, low, high = kc.vector
        obs_kernels.vectors_of(*args, c, low, high, vec[0])
        obs_kernels.vectors(*args, *c.tolist(), low, high, vec[1])
        _same(vec[0], vec[1], "vectors")

    a = rng.uniform(-1, 1, (6, 3))
    assert kernel.all_finite(a)
    for bad in (np.nan, np.inf, -np.inf):
        b = a.copy()
        b[5, 2] = bad
        assert not kernel.all_finite(b) and not np.isfinite(b).all()
