"""Population optimisers with one scipy-style front end: the paper's adaptive DE and its rivals.

Every optimiser here is a function ``name(func, bounds, *, popsize=100, maxiter=300, ...,
rng=None, callback=None, vectorized=True) -> OptimizeResult`` that *minimises* ``func`` over the
box ``bounds``:

``adaptive_de``
    The paper's method (§4, eq. 27-32): DE/rand/1/bin whose mutation factor decays from
    ``2 F0`` to ``F0`` (eq. 32); optionally staged (§4.5).
``classic_de``
    The same DE with a constant ``F = F0`` (the paper's "classic DE" of Fig. 22).
``chaotic_abc``
    Artificial bee colony with logistic-map (chaotic) initialisation and scout re-seeding, in
    the spirit of the paper's [34].
``grouped_pso``
    Particle swarm with sub-swarms that exchange their best periodically, in the spirit of the
    paper's [40].
``scipy_de``
    :func:`scipy.optimize.differential_evolution` (its default ``best1bin`` strategy, dithered
    mutation, ``recombination=0.7``), started from the same uniform population.
``cmaes``
    CMA-ES of the ``cma`` package on the box scaled to ``[0, 1]^D``.

Conventions shared by all:

* ``func`` takes a population ``X`` of shape (P, D) -- one individual per *row* -- and returns
  (P,) values (``vectorized=True``, the default); with ``vectorized=False`` it takes one (D,)
  vector and returns a float. (scipy's own ``vectorized`` passes (D, P); :func:`scipy_de`
  transposes.) NaN values count as +inf.
* ``rng``: ``None`` (fresh entropy), an int seed or a :class:`numpy.random.Generator`. No global
  random state is read or left changed: equal seeds give identical histories and results.
* Budget parity: each uses about ``popsize x (maxiter + 1)`` evaluations -- the DEs, scipy and
  the PSO evaluate an initial population of ``popsize`` and then ``popsize`` trials per
  generation; the bee colony has ``popsize // 2`` food sources, each cycle ``popsize // 2``
  employed and as many onlooker trials plus at most one scout; CMA-ES starts from the best of
  an initial uniform population of ``popsize`` and samples ``popsize`` per iteration.
* The result is a :class:`scipy.optimize.OptimizeResult` with ``x``, ``fun``, ``nit``,
  ``nfev``, ``success``, ``message`` and ``history`` (``nit + 1`` best-so-far values: the
  initial population's best, then one per generation / cycle / iteration).
* ``callback(intermediate_result)`` is called after every generation with an
  ``OptimizeResult`` (``x``, ``fun``, ``nit``, ``nfev`` and, where there is one,
  ``population``); returning ``True`` (or raising ``StopIteration``) stops the run.

``OPTIMIZERS`` maps the names to the functions; :func:`get_optimizer` rejects unknown names
with a :class:`~poc_env.errors.ConfigError` listing the allowed ones, and :func:`run_optimizer`
maps a scenario's ``planner`` section (population, generations, f0, cr) onto any of them.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from scipy.optimize import OptimizeResult

from poc_env.errors import ConfigError

__all__ = [
    "OPTIMIZERS",
    "PRESETS",
    "TUNED_DE",
    "adaptive_de",
    "adaptive_mutation",
    "chaotic_abc",
    "classic_de",
    "cmaes",
    "get_optimizer",
    "grouped_pso",
    "preset_settings",
    "run_optimizer",
    "scipy_de",
]

Objective = Callable[[np.ndarray], Any]


# --------------------------------------------------------------------------- shared helpers


def _as_rng(rng) -> np.random.Generator:
    if rng is None or (isinstance(rng, (int, np.integer)) and not isinstance(rng, bool)):
        return np.random.default_rng(rng)
    if isinstance(rng, np.random.Generator):
        return rng
    raise ConfigError("rng", rng, "None, an int seed or a numpy.random.Generator")


def _check_bounds(bounds) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) arrays from (low, high) pairs or an object with ``lb``/``ub``."""
    allowed = "a non-empty sequence of (low, high) pairs with finite low < high"
    try:
        if hasattr(bounds, "lb") and hasattr(bounds, "ub"):
            lo = np.atleast_1d(np.asarray(bounds.lb, dtype=float))
            hi = np.atleast_1d(np.asarray(bounds.ub, dtype=float))
        else:
            b = np.asarray(bounds, dtype=float)
            if b.ndim != 2 or b.shape[1] != 2:
                raise ValueError
            lo, hi = b[:, 0].copy(), b[:, 1].copy()
    except (TypeError, ValueError):
        raise ConfigError("bounds", bounds, allowed) from None
    if lo.size == 0 or lo.shape != hi.shape:
        raise ConfigError("bounds", bounds, allowed)
    bad = ~(np.isfinite(lo) & np.isfinite(hi) & (lo < hi))
    if np.any(bad):
        j = int(np.flatnonzero(bad)[0])
        raise ConfigError(f"bounds[{j}]", (float(lo[j]), float(hi[j])), allowed)
    return lo, hi


def _check_int(name: str, value, lo: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < lo:
        raise ConfigError(name, value, f"an integer >= {lo}")
    return int(value)


def _check_unit(name: str, value, lo: float, hi: float) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ConfigError(name, value, f"a number in [{lo}, {hi}]") from None
    if isinstance(value, bool) or not lo <= v <= hi:
        raise ConfigError(name, value, f"a number in [{lo}, {hi}]")
    return v


class _Counted:
    """``func`` as a population evaluator (P, D) -> (P,) that counts evaluations."""

    def __init__(self, func: Objective, vectorized: bool) -> None:
        if not callable(func):
            raise ConfigError("func", func, "a callable")
        self.func = func
        self.vectorized = bool(vectorized)
        self.nfev = 0

    def __call__(self, pop: np.ndarray) -> np.ndarray:
        if self.vectorized:
            f = np.asarray(self.func(pop), dtype=float).reshape(-1)
        else:  # the user's scalar function, one individual at a time
            f = np.array([float(self.func(x)) for x in pop])
        if f.shape != (len(pop),):
            raise ValueError(f"func returned shape {f.shape} for a population of {len(pop)}")
        self.nfev += len(pop)
        return np.where(np.isnan(f), np.inf, f)


def _uniform(rng: np.random.Generator, lo: np.ndarray, hi: np.ndarray, n: int) -> np.ndarray:
    """Eq. 28: ``rand[0, 1] (x_U - x_L) + x_L`` for ``n`` individuals."""
    return lo + rng.random((n, lo.size)) * (hi - lo)


def _notify(callback, x, fun, nit, nfev, population=None) -> bool:
    """Call the user's callback; True when it asks to stop."""
    if callback is None:
        return False
    res = OptimizeResult(x=np.array(x), fun=float(fun), nit=nit, nfev=nfev)
    if population is not None:
        res.population = np.array(population)
    try:
        return bool(callback(res))
    except StopIteration:
        return True


def _result(x, fun, nit, nfev, history, stopped: bool, **extra) -> OptimizeResult:
    message = (
        "callback requested stop" if stopped else "Maximum number of iterations has been reached."
    )
    return OptimizeResult(
        x=np.array(x),
        fun=float(fun),
        nit=int(nit),
        nfev=int(nfev),
        success=True,
        message=message,
        history=np.asarray(history, dtype=float),
        **extra,
    )


# --------------------------------------------------------------------------- DE (eq. 27-32)


def adaptive_mutation(generation, max_generations, f0: float = 0.2):
    """The adaptive mutation factor of eq. 32, ``F = 2^lambda F0``.

    ``lambda = exp(1 - Gm / (Gm - G))`` with ``G`` the 0-based generation (the number of
    generations already completed) and ``Gm`` the number of generations. The paper counts
    generations from 1 (§4.4, Step 1: "the number of generations initialized to 1") and prints
    ``lambda = exp(1 - Gm / (Gm + 1 - G_paper))``; with ``G_paper = G + 1`` that is the form
    above, and it gives what the paper says of it: ``F = 2 F0`` exactly at the first
    generation (``G = 0``), decreasing monotonically to ``F0`` at ``G = Gm`` (``lambda -> 0``;
    the last generation run, ``G = Gm - 1``, has ``lambda = e^(1 - Gm)``). Broadcasts over
    ``generation``.
    """
    g = np.asarray(generation, dtype=float)
    gm = float(max_generations)
    with np.errstate(divide="ignore"):
        ratio = np.where(g < gm, gm / np.maximum(gm - g, 0.0), np.inf)
    lam = np.exp(1.0 - ratio)
    return 2.0**lam * f0


def _stages(staged, dim: int, maxiter: int) -> list[tuple[np.ndarray, int]]:
    """[(coordinates evolved, generations), ...] of a (staged) DE run."""
    if staged is False or staged is None:
        return [(np.arange(dim), maxiter)]
    if staged is True:
        if dim % 6:
            raise ConfigError(
                "staged", True, "True only for the 6n encoding (x, y, l, w, theta, d) per UAV"
            )
        base = np.arange(0, dim, 6)
        groups = [np.sort(np.concatenate([base + k, base + k + 1])) for k in (0, 2, 4)]
    else:
        try:
            groups = [np.unique(np.asarray(g, dtype=int).reshape(-1)) for g in staged]
        except (TypeError, ValueError):
            raise ConfigError("staged", staged, "a bool or a list of index lists") from None
        if not groups or any(g.size == 0 or g.min() < 0 or g.max() >= dim for g in groups):
            raise ConfigError("staged", staged, f"non-empty index lists within [0, {dim})")
    k = len(groups)
    if maxiter < k:
        raise ConfigError("maxiter", maxiter, f"at least {k} generations for {k} stages")
    sizes = [maxiter // k + (1 if s < maxiter % k else 0) for s in range(k)]
    return list(zip(groups, sizes))


def _de(
    func,
    bounds,
    *,
    popsize: int,
    maxiter: int,
    f0: float,
    cr: float,
    rng,
    callback,
    staged,
    vectorized: bool,
    adaptive: bool,
    init=None,
) -> OptimizeResult:
    lo, hi = _check_bounds(bounds)
    npop = _check_int("popsize", popsize, 4)
    maxiter = _check_int("maxiter", maxiter, 0)
    f0 = _check_unit("f0", f0, 0.0, 2.0)
    cr = _check_unit("cr", cr, 0.0, 1.0)
    gen = _as_rng(rng)
    evaluate = _Counted(func, vectorized)
    dim = lo.size
    stages = _stages(staged, dim, maxiter) if maxiter else []

    pop = _uniform(gen, lo, hi, npop)  # eq. 27-28
    if init is not None:  # given individuals replace the first rows (scipy's init=array)
        given = np.atleast_2d(np.asarray(init, dtype=float))
        if given.ndim != 2 or given.shape[1] != dim or not 1 <= len(given) <= npop:
            raise ConfigError("init", given.shape, f"an array (k, {dim}) with 1 <= k <= {npop}")
        if not np.all((given >= lo) & (given <= hi)):
            raise ConfigError("init", "individuals outside the bounds", "rows within the bounds")
        pop[: len(given)] = given
    energy = evaluate(pop)
    best = int(np.argmin(energy))
    history = [energy[best]]
    mutation: list[float] = []
    rows = np.arange(npop)
    nit = 0
    stopped = False
    for coords, n_gen in stages:
        for g in range(n_gen):
            f = float(adaptive_mutation(g, n_gen, f0)) if adaptive else f0
            mutation.append(f)
            # eq. 29, DE/rand/1: r1, r2, r3 distinct and != i, a uniformly random ordered triple
            keys = gen.random((npop, npop))
            keys[rows, rows] = np.inf
            pick = np.argpartition(keys, 2, axis=1)[:, :3]
            order = np.argsort(np.take_along_axis(keys, pick, axis=1), axis=1)
            r = np.take_along_axis(pick, order, axis=1)
            sub = pop[:, coords]
            mutant = sub[r[:, 0]] + f * (sub[r[:, 1]] - sub[r[:, 2]])
            # eq. 30, binomial crossover; rnbr(i) guarantees one mutant coordinate
            cross = gen.random((npop, coords.size)) <= cr
            cross[rows, gen.integers(coords.size, size=npop)] = True
            trial = pop.copy()
            trial[:, coords] = np.where(cross, mutant, sub)
            # eq. 31: coordinates outside the bounds are drawn afresh, uniformly within them
            fresh = _uniform(gen, lo, hi, npop)
            out = (trial < lo) | (trial > hi)
            trial = np.where(out, fresh, trial)
            # greedy selection
            t_energy = evaluate(trial)
            better = t_energy <= energy
            pop[better] = trial[better]
            energy[better] = t_energy[better]
            best = int(np.argmin(energy))
            history.append(energy[best])
            nit += 1
            if _notify(callback, pop[best], energy[best], nit, evaluate.nfev, pop):
                stopped = True
                break
        if stopped:
            break
    return _result(
        pop[best],
        energy[best],
        nit,
        evaluate.nfev,
        history,
        stopped,
        population=pop,
        population_energies=energy,
        mutation=np.asarray(mutation),
    )


def adaptive_de(
    func: Objective,
    bounds,
    *,
    popsize: int = 100,
    maxiter: int = 300,
    f0: float = 0.2,
    cr: float = 0.1,
    rng=None,
    callback=None,
    staged: bool | Sequence[Sequence[int]] = False,
    vectorized: bool = True,
    init=None,
) -> OptimizeResult:
    """Minimise ``func`` with the paper's adaptive differential evolution (eq. 27-32).

    Parameters
    ----------
    func : callable
        ``func(X) -> (P,)`` for a population ``X`` of shape (P, D), one individual per row
        (``vectorized=True``); or ``func(x) -> float`` for one (D,) vector.
    bounds : sequence of (low, high) or scipy.optimize.Bounds
        The box of eq. 28, finite ``low < high`` for each of the D variables.
    popsize : int, default 100
        NP, the number of individuals (eq. 27), >= 4.
    maxiter : int, default 300
        Gm, the number of generations.
    f0 : float, default 0.2
        F0 of eq. 32; the mutation factor runs from ``2 F0`` down to ``F0``.
    cr : float, default 0.1
        CR, the crossover probability of eq. 30.
    rng : None, int or numpy.random.Generator
        Seed or generator; the run is reproducible for a given seed.
    callback : callable, optional
        ``callback(intermediate_result)`` after every generation; return True to stop.
    staged : bool or list of index lists, default False
        The step-by-step variant of §4.5. ``True`` (for the 6n encoding of
        :mod:`poc_env.agents.planning.objective`): three stages that evolve first every UAV's
        position
        ``(x_c, y_c)``, then its size ``(l, w)``, then its angle and spacing ``(theta, d)``;
        a list of index lists gives custom stages. The generations are split evenly between
        the stages (the first ``maxiter % k`` stages get one more). During a stage, mutation
        and crossover touch only that stage's coordinates (``rnbr`` is drawn among them); the
        others are carried over from the target individual unchanged. Eq. 32 restarts in each
        stage (``G`` counted within the stage, ``Gm`` its length), so every stage begins with a
        broad search and ends with a fine one. The budget is the same as unstaged.
    vectorized : bool, default True
        Whether ``func`` takes the whole population at once.
    init : array (k, D), optional
        Individuals that replace the first ``k`` of the uniformly drawn initial population
        (a warm start, as scipy's ``init=`` array); they must lie within the bounds.

    Returns
    -------
    OptimizeResult
        ``x``, ``fun``, ``nit``, ``nfev`` (``popsize x (nit + 1)``), ``success``, ``message``,
        ``history`` (best value of the initial population, then after each generation),
        ``mutation`` (F of each generation), ``population`` and ``population_energies``.

    Notes
    -----
    Each generation ``G = 0, ..., Gm - 1`` of the population ``x_i`` (eq. 27, initialised
    uniformly within the bounds, eq. 28):

    1. mutation factor (eq. 32): ``F = 2^lambda F0``, ``lambda = exp(1 - Gm / (Gm - G))`` --
       the paper's formula with its 1-based generation counter, see :func:`adaptive_mutation`;
       ``F = 2 F0`` at ``G = 0`` and it falls to ``F0``;
    2. mutation DE/rand/1 (eq. 29): ``v_i = x_r1 + F (x_r2 - x_r3)``, ``r1, r2, r3`` distinct
       random indices other than ``i``;
    3. binomial crossover (eq. 30): ``u_ji = v_ji`` if ``rand(j) <= CR`` or ``j = rnbr(i)``,
       else ``x_ji``;
    4. abnormal individuals (eq. 31): a coordinate of ``u_i`` outside the bounds is replaced by
       ``rand[0, 1] (x_U - x_L) + x_L``;
    5. greedy selection: ``u_i`` replaces ``x_i`` when ``f(u_i) <= f(x_i)``.

    References
    ----------
    .. [1] Fan, X., Li, H., Chen, Y., Dong, D. "UAV Swarm Search Path Planning Method Based on
       Probability of Containment", Drones 8(4), 132 (2024), §4, eq. 27-32.
    .. [2] Storn, R., Price, K. "Differential Evolution -- A Simple and Efficient Heuristic for
       Global Optimization over Continuous Spaces", J. Global Optim. 11, 341-359 (1997).

    Examples
    --------
    >>> import numpy as np
    >>> from poc_env.agents.planning.optimizers import adaptive_de
    >>> sphere = lambda X: np.sum((X - 1.0) ** 2, axis=1)
    >>> res = adaptive_de(sphere, [(-5, 5)] * 4, popsize=30, maxiter=200, f0=0.3, cr=0.9, rng=1)
    >>> bool(res.fun < 1e-6), res.nfev
    (True, 6030)
    """
    return _de(
        func,
        bounds,
        popsize=popsize,
        maxiter=maxiter,
        f0=f0,
        cr=cr,
        rng=rng,
        callback=callback,
        staged=staged,
        vectorized=vectorized,
        adaptive=True,
        init=init,
    )


def classic_de(
    func: Objective,
    bounds,
    *,
    popsize: int = 100,
    maxiter: int = 300,
    f0: float = 0.2,
    cr: float = 0.1,
    rng=None,
    callback=None,
    staged: bool | Sequence[Sequence[int]] = False,
    vectorized: bool = True,
    init=None,
) -> OptimizeResult:
    """Classic DE/rand/1/bin with a constant mutation factor ``F = f0`` (the paper's Fig. 22).

    Identical to :func:`adaptive_de` (eq. 27-31, same random stream) except that eq. 32 is
    replaced by the constant ``F = F0``: in the paper's comparison classic DE uses the base
    factor, so the adaptive variant starts with twice its step. Parameters and result as in
    :func:`adaptive_de`.
    """
    return _de(
        func,
        bounds,
        popsize=popsize,
        maxiter=maxiter,
        f0=f0,
        cr=cr,
        rng=rng,
        callback=callback,
        staged=staged,
        vectorized=vectorized,
        adaptive=False,
        init=init,
    )


# --------------------------------------------------------------------------- chaotic ABC


class _Logistic:
    """The logistic map ``z <- 4 z (1 - z)`` per coordinate, reseeded if it collapses."""

    def __init__(self, rng: np.random.Generator, dim: int, burn_in: int = 50) -> None:
        self.rng = rng
        self.z = rng.uniform(0.05, 0.95, dim)
        for _ in range(burn_in):
            self.step()

    def step(self) -> np.ndarray:
        z = 4.0 * self.z * (1.0 - self.z)
        # floating-point orbits can fall onto the fixed points 0 and 3/4 (or their preimages)
        stuck = (z < 1e-9) | (z > 1 - 1e-9) | (np.abs(z - 0.75) < 1e-9) | (z == self.z)
        if np.any(stuck):
            z[stuck] = self.rng.uniform(0.05, 0.95, int(stuck.sum()))
        self.z = z
        return z.copy()

    def population(self, n: int) -> np.ndarray:
        return np.array([self.step() for _ in range(n)])


def chaotic_abc(
    func: Objective,
    bounds,
    *,
    popsize: int = 100,
    maxiter: int = 300,
    limit: int | None = None,
    rng=None,
    callback=None,
    vectorized: bool = True,
) -> OptimizeResult:
    """Minimise ``func`` with a chaotic artificial bee colony (the paper's [34]).

    Parameters
    ----------
    func, bounds, rng, callback, vectorized
        As in :func:`adaptive_de`.
    popsize : int, default 100
        Colony size: ``popsize // 2`` food sources, as many employed bees and onlookers.
    maxiter : int, default 300
        Number of cycles.
    limit : int, optional
        Failed trials after which a source is abandoned to a scout; default ``2 D`` so that
        scouts fire within the paper's budget (Karaboga's ``SN x D`` would never fire in 300
        cycles for D = 36).

    Returns
    -------
    OptimizeResult
        As :func:`adaptive_de`; ``population`` holds the food sources. ``x``/``fun`` are the
        best ever found (a scout may abandon it).

    Notes
    -----
    Karaboga's ABC [2] with the chaotic ingredients of Alatas [3]: the initial food sources and
    every scout's new source are drawn from a logistic map ``z <- 4 z (1 - z)`` (one chaotic
    sequence per coordinate, ``x = x_L + z (x_U - x_L)``) instead of uniform noise, so
    re-seeding keeps sweeping the whole box. Each cycle: every employed bee tries
    ``v_ij = x_ij + phi (x_ij - x_kj)`` for one random coordinate ``j``, random ``k != i``,
    ``phi ~ U(-1, 1)`` (clipped to the bounds) and keeps it if not worse; onlookers pick sources
    with probability proportional to the fitness ``1 / (1 + f)`` (``1 + |f|`` for ``f < 0``) and
    do the same (the best onlooker trial of a source competes with it); the source with the
    most failed trials beyond ``limit`` is replaced by a chaotic scout.

    References
    ----------
    .. [1] Fan et al., Drones 8(4), 132 (2024), ref. [34] and §6.3.2.
    .. [2] Karaboga, D., Basturk, B. "A powerful and efficient algorithm for numerical function
       optimization: artificial bee colony (ABC) algorithm", J. Global Optim. 39 (2007).
    .. [3] Alatas, B. "Chaotic bee colony algorithms for global numerical optimization",
       Expert Syst. Appl. 37, 5682-5687 (2010).

    Examples
    --------
    >>> import numpy as np
    >>> from poc_env.agents.planning.optimizers import chaotic_abc
    >>> res = chaotic_abc(lambda X: np.sum(X**2, axis=1), [(-5, 5)] * 3, popsize=20,
    ...                   maxiter=100, rng=0)
    >>> bool(res.fun < 1e-2)
    True
    """
    lo, hi = _check_bounds(bounds)
    npop = _check_int("popsize", popsize, 4)
    maxiter = _check_int("maxiter", maxiter, 0)
    dim = lo.size
    limit = 2 * dim if limit is None else _check_int("limit", limit, 1)
    gen = _as_rng(rng)
    evaluate = _Counted(func, vectorized)
    sn = npop // 2
    chaos = _Logistic(gen, dim)
    food = lo + chaos.population(sn) * (hi - lo)
    energy = evaluate(food)
    trials = np.zeros(sn, dtype=int)
    b = int(np.argmin(energy))
    best_x, best_f = food[b].copy(), float(energy[b])
    history = [best_f]
    rows = np.arange(sn)

    def neighbours(src: np.ndarray) -> np.ndarray:
        partner = (src + gen.integers(1, sn, size=src.size)) % sn
        j = gen.integers(dim, size=src.size)
        phi = gen.uniform(-1.0, 1.0, size=src.size)
        v = food[src].copy()
        k = np.arange(src.size)
        v[k, j] = np.clip(food[src, j] + phi * (food[src, j] - food[partner, j]), lo[j], hi[j])
        return v

    nit = 0
    stopped = False
    for _ in range(maxiter):
        # employed bees
        cand = neighbours(rows)
        fc = evaluate(cand)
        ok = fc <= energy
        food[ok], energy[ok] = cand[ok], fc[ok]
        trials = np.where(ok, 0, trials + 1)
        # onlookers
        pos_part = np.where(energy >= 0, energy, 0.0)
        fit = np.where(energy >= 0, 1.0 / (1.0 + pos_part), 1.0 + np.abs(energy))
        fit = np.where(np.isfinite(fit), fit, 0.0)
        prob = fit / fit.sum() if fit.sum() > 0 else np.full(sn, 1.0 / sn)
        src = gen.choice(sn, size=sn, p=prob)
        cand = neighbours(src)
        fc = evaluate(cand)
        order = np.lexsort((fc, src))  # by source, then value
        first = np.ones(sn, dtype=bool)
        first[1:] = src[order][1:] != src[order][:-1]
        winners = order[first]
        s_w = src[winners]
        ok = fc[winners] <= energy[s_w]
        food[s_w[ok]], energy[s_w[ok]] = cand[winners[ok]], fc[winners[ok]]
        counts = np.bincount(src, minlength=sn)
        improved = np.zeros(sn, dtype=bool)
        improved[s_w[ok]] = True
        trials = np.where(improved, 0, trials + counts)
        # remember the best before a scout may abandon it
        b = int(np.argmin(energy))
        if energy[b] < best_f:
            best_x, best_f = food[b].copy(), float(energy[b])
        # scout: the most exhausted source beyond the limit is re-seeded chaotically
        w = int(np.argmax(trials))
        if trials[w] > limit:
            food[w] = lo + chaos.step() * (hi - lo)
            energy[w] = evaluate(food[w][None])[0]
            trials[w] = 0
            if energy[w] < best_f:
                best_x, best_f = food[w].copy(), float(energy[w])
        history.append(best_f)
        nit += 1
        if _notify(callback, best_x, best_f, nit, evaluate.nfev, food):
            stopped = True
            break
    return _result(
        best_x,
        best_f,
        nit,
        evaluate.nfev,
        history,
        stopped,
        population=food,
        population_energies=energy,
    )


# --------------------------------------------------------------------------- grouped PSO


def grouped_pso(
    func: Objective,
    bounds,
    *,
    popsize: int = 100,
    maxiter: int = 300,
    groups: int = 4,
    exchange_every: int = 25,
    inertia: tuple[float, float] = (0.9, 0.4),
    c1: float = 1.5,
    c2: float = 1.5,
    rng=None,
    callback=None,
    vectorized: bool = True,
) -> OptimizeResult:
    """Minimise ``func`` with a particle swarm of sub-swarms that exchange information ([40]).

    Parameters
    ----------
    func, bounds, rng, callback, vectorized
        As in :func:`adaptive_de`.
    popsize : int, default 100
        Number of particles, split into ``groups`` sub-swarms of (nearly) equal size.
    maxiter : int, default 300
        Number of iterations.
    groups : int, default 4
        Number of sub-swarms (each needs at least 2 particles).
    exchange_every : int, default 25
        Iterations between information exchanges.
    inertia : (float, float), default (0.9, 0.4)
        Inertia weight, decreased linearly from the first to the second value.
    c1, c2 : float, default 1.5
        Cognitive (own best) and social (sub-swarm best) acceleration.

    Returns
    -------
    OptimizeResult
        As :func:`adaptive_de`; ``population`` holds the particles' personal bests.

    Notes
    -----
    Each particle moves by ``v <- w v + c1 r1 (p - x) + c2 r2 (g_k - x)``, ``x <- x + v``, where
    ``p`` is its own best and ``g_k`` the best of its sub-swarm ``k`` only; speeds are limited
    to 20 % of the box per coordinate, and a coordinate leaving the box is put on the bound
    with its speed set to 0. Between exchanges the sub-swarms search independently (slow
    early progress, the paper's blue curve of Fig. 22); every ``exchange_every`` iterations the
    overall best personal best replaces the worst personal best (and the position) of every
    other sub-swarm, so all sub-swarms move towards the best region found.

    References
    ----------
    .. [1] Fan et al., Drones 8(4), 132 (2024), ref. [40] and §6.3.2.
    .. [2] Kennedy, J., Eberhart, R. "Particle swarm optimization", Proc. ICNN'95 (1995).

    Examples
    --------
    >>> import numpy as np
    >>> from poc_env.agents.planning.optimizers import grouped_pso
    >>> res = grouped_pso(lambda X: np.sum(X**2, axis=1), [(-5, 5)] * 3, popsize=20,
    ...                   maxiter=100, rng=0)
    >>> bool(res.fun < 1e-2)
    True
    """
    lo, hi = _check_bounds(bounds)
    npop = _check_int("popsize", popsize, 4)
    maxiter = _check_int("maxiter", maxiter, 0)
    k = _check_int("groups", groups, 1)
    if npop < 2 * k:
        raise ConfigError("groups", groups, f"at most popsize / 2 = {npop // 2}")
    exchange_every = _check_int("exchange_every", exchange_every, 1)
    w0, w1 = (float(v) for v in inertia)
    gen = _as_rng(rng)
    evaluate = _Counted(func, vectorized)
    dim = lo.size
    span = hi - lo
    vmax = 0.2 * span
    x = _uniform(gen, lo, hi, npop)
    v = gen.uniform(-1.0, 1.0, (npop, dim)) * vmax
    fx = evaluate(x)
    p, fp = x.copy(), fx.copy()
    group = np.arange(npop) % k
    members = [np.flatnonzero(group == g) for g in range(k)]
    history = [float(fp.min())]
    nit = 0
    stopped = False
    for it in range(maxiter):
        w = w0 + (w1 - w0) * (it / max(maxiter - 1, 1))
        gbest = np.empty((npop, dim))
        for idx in members:  # a loop over the few sub-swarms
            gbest[idx] = p[idx[np.argmin(fp[idx])]]
        r1 = gen.random((npop, dim))
        r2 = gen.random((npop, dim))
        v = w * v + c1 * r1 * (p - x) + c2 * r2 * (gbest - x)
        v = np.clip(v, -vmax, vmax)
        x = x + v
        hit = (x < lo) | (x > hi)
        x = np.clip(x, lo, hi)
        v = np.where(hit, 0.0, v)
        fx = evaluate(x)
        ok = fx <= fp
        p[ok], fp[ok] = x[ok], fx[ok]
        if (it + 1) % exchange_every == 0 and k > 1:
            b = int(np.argmin(fp))
            for idx in members:
                if group[b] == group[idx[0]]:
                    continue
                worst = idx[np.argmax(fp[idx])]
                p[worst], fp[worst], x[worst] = p[b], fp[b], p[b]
        b = int(np.argmin(fp))
        history.append(float(fp[b]))
        nit += 1
        if _notify(callback, p[b], fp[b], nit, evaluate.nfev, p):
            stopped = True
            break
    b = int(np.argmin(fp))
    return _result(
        p[b], fp[b], nit, evaluate.nfev, history, stopped, population=p, population_energies=fp
    )


# --------------------------------------------------------------------------- scipy and CMA-ES


def scipy_de(
    func: Objective,
    bounds,
    *,
    popsize: int = 100,
    maxiter: int = 300,
    strategy: str = "best1bin",
    mutation: float | tuple[float, float] = (0.5, 1.0),
    recombination: float = 0.7,
    rng=None,
    callback=None,
    vectorized: bool = True,
) -> OptimizeResult:
    """:func:`scipy.optimize.differential_evolution` with this module's conventions and budget.

    The initial population is ``popsize`` uniform individuals (eq. 28, from ``rng``) passed as
    scipy's ``init``, so the population size is exactly ``popsize`` (scipy's own ``popsize`` is a
    multiplier of D); ``updating="deferred"``, ``vectorized`` as given (scipy's (D, P) layout is
    transposed for ``func``), ``tol = atol = 0`` so that it runs all ``maxiter`` generations,
    ``polish=False`` (no extra L-BFGS-B evaluations). ``strategy``, ``mutation`` and
    ``recombination`` are scipy's (its defaults). Result as :func:`adaptive_de`.

    Examples
    --------
    >>> import numpy as np
    >>> from poc_env.agents.planning.optimizers import scipy_de
    >>> res = scipy_de(lambda X: np.sum(X**2, axis=1), [(-5, 5)] * 3, popsize=20,
    ...                maxiter=100, rng=0)
    >>> bool(res.fun < 1e-6), res.nfev
    (True, 2020)
    """
    from scipy.optimize import differential_evolution

    lo, hi = _check_bounds(bounds)
    npop = _check_int("popsize", popsize, 5)
    maxiter = _check_int("maxiter", maxiter, 1)
    gen = _as_rng(rng)
    evaluate = _Counted(func, vectorized)
    init = _uniform(gen, lo, hi, npop)
    history: list[float] = []
    state = {"stopped": False, "nit": 0}

    def f(xt):
        pop = np.asarray(xt, dtype=float)
        values = evaluate(pop.T if pop.ndim == 2 else pop[None])
        if not history:  # the first call evaluates the initial population
            history.append(float(values.min()))
        return values if pop.ndim == 2 else values[0]

    def cb(intermediate_result):
        state["nit"] += 1
        history.append(min(float(intermediate_result.fun), history[-1]))
        if _notify(callback, intermediate_result.x, history[-1], state["nit"], evaluate.nfev):
            state["stopped"] = True
            return True
        return False

    kwargs: dict[str, Any] = {}
    params = inspect.signature(differential_evolution).parameters
    kwargs["rng" if "rng" in params else "seed"] = gen
    res = differential_evolution(
        f,
        list(zip(lo, hi)),
        strategy=strategy,
        maxiter=maxiter,
        popsize=1,
        tol=0.0,
        atol=0.0,
        mutation=mutation,
        recombination=recombination,
        callback=cb,
        polish=False,
        init=init,
        updating="deferred",
        vectorized=True,
        **kwargs,
    )
    return _result(
        res.x,
        res.fun,
        state["nit"],
        evaluate.nfev,
        history,
        bool(state["stopped"]),
        population=getattr(res, "population", None),
        population_energies=getattr(res, "population_energies", None),
    )


def cmaes(
    func: Objective,
    bounds,
    *,
    popsize: int = 100,
    maxiter: int = 300,
    sigma0: float = 0.3,
    rng=None,
    callback=None,
    vectorized: bool = True,
) -> OptimizeResult:
    """CMA-ES (the ``cma`` package) on the box scaled to ``[0, 1]^D``.

    ``popsize`` uniform individuals (eq. 28) are evaluated first; CMA-ES starts from the best
    of them with step ``sigma0`` (in units of the box) and samples ``popsize`` candidates per
    iteration for ``maxiter`` iterations, the box enforced by cma's ``BoundTransform``. Normal
    samples come from ``rng`` (cma's ``randn`` option, its ``seed`` set to "do nothing"), and
    numpy's global random state is restored afterwards, so runs are reproducible and side-effect
    free. cma's own convergence stops are relaxed so that the budget is spent (a run that
    still stops early reports it in ``message``). Result as :func:`adaptive_de`; ``x``/``fun``
    are the best ever evaluated.

    Examples
    --------
    >>> import numpy as np
    >>> from poc_env.agents.planning.optimizers import cmaes
    >>> res = cmaes(lambda X: np.sum(X**2, axis=1), [(-5, 5)] * 3, popsize=10, maxiter=100,
    ...             rng=0)
    >>> bool(res.fun < 1e-6)
    True
    """
    try:
        import cma
    except ImportError as err:  # pragma: no cover - cma is a declared dependency
        raise ConfigError(
            "optimizer", "cmaes", "installed 'cma' (pip install -c constraints.txt cma)"
        ) from err
    lo, hi = _check_bounds(bounds)
    npop = _check_int("popsize", popsize, 2)
    maxiter = _check_int("maxiter", maxiter, 0)
    gen = _as_rng(rng)
    evaluate = _Counted(func, vectorized)
    span = hi - lo
    start = _uniform(gen, lo, hi, npop)
    f_start = evaluate(start)
    b = int(np.argmin(f_start))
    best_x, best_f = start[b].copy(), float(f_start[b])
    history = [best_f]
    nit = 0
    stopped = False
    message = "Maximum number of iterations has been reached."
    if maxiter == 0:
        return _result(best_x, best_f, 0, evaluate.nfev, history, False)
    z0 = (best_x - lo) / span
    opts = {
        "popsize": npop,
        "bounds": [0.0, 1.0],
        "seed": np.nan,
        "randn": lambda lam, n: gen.standard_normal((lam, n)),
        "verbose": -9,
        "maxiter": maxiter,
        "tolfun": 0.0,
        "tolfunhist": 0.0,
        "tolx": 0.0,
        "tolflatfitness": maxiter + 1,
        "tolstagnation": maxiter + 1,
    }
    saved = np.random.get_state()  # noqa: NPY002 - restored: cma may touch it
    try:
        es = cma.CMAEvolutionStrategy(z0, sigma0, opts)
        for _ in range(maxiter):
            zs = np.asarray(es.ask())
            xs = lo + np.clip(zs, 0.0, 1.0) * span
            fs = evaluate(xs)
            es.tell(list(zs), fs.tolist())
            k = int(np.argmin(fs))
            if fs[k] < best_f:
                best_x, best_f = xs[k].copy(), float(fs[k])
            history.append(best_f)
            nit += 1
            if _notify(callback, best_x, best_f, nit, evaluate.nfev):
                stopped = True
                break
            halt = {k: v for k, v in es.stop().items() if k != "maxiter"}
            if halt:
                message = f"cma stopped early: {halt}"
                break
    finally:
        np.random.set_state(saved)  # noqa: NPY002
    res = _result(best_x, best_f, nit, evaluate.nfev, history, stopped)
    if not stopped:
        res.message = message
    return res


# --------------------------------------------------------------------------- registry

OPTIMIZERS: dict[str, Callable[..., OptimizeResult]] = {
    "adaptive_de": adaptive_de,
    "classic_de": classic_de,
    "chaotic_abc": chaotic_abc,
    "grouped_pso": grouped_pso,
    "scipy_de": scipy_de,
    "cmaes": cmaes,
}


def get_optimizer(name: str) -> Callable[..., OptimizeResult]:
    """The optimiser called ``name``; ConfigError naming ``optimizer`` and the allowed names."""
    fn = OPTIMIZERS.get(name) if isinstance(name, str) else None
    if fn is None:
        raise ConfigError("optimizer", name, "one of " + ", ".join(OPTIMIZERS))
    return fn


# ------------------------------------------------------------------------------------ presets

#: The DE settings presets of ``poc-env plan --preset`` / ``poc-env experiment --preset``.
PRESETS = ("paper", "tuned")

#: ``tuned``: the mutation and crossover constants of adaptive DE (eq. 30, 32) chosen by the
#: sweep in docs/PLANNER.md (section 4): paper_6_2, 6 UAVs, the paper's budget NP = 100,
#: G = 300, picked on seeds 0-2 among CR 0.1-1.0 and F0 0.1-0.4 (and NP/G trades of the same
#: or a larger budget), checked on seeds 3-8: best eq. 26 objective -0.383 +- 0.012 against the
#: paper's -0.303 +- 0.008, in the same time. ``CR = 0.9`` lets a trial move several UAVs'
#: coordinates together (the objective is not separable: rectangles interact through the
#: overlap rule of §3.1.6); the smaller ``F0`` keeps those moves short.
TUNED_DE: dict[str, float] = {"f0": 0.15, "cr": 0.9}


def preset_settings(preset: str, planner) -> dict[str, Any]:
    """``popsize``, ``maxiter``, ``f0`` and ``cr`` of a settings preset.

    ``paper``: the scenario's ``planner`` section (:class:`~poc_env.config.PlannerConfig`: the
    paper's NP = 100, G = 300, F0 = 0.2, CR = 0.1 in the built-in scenarios), unchanged.
    ``tuned``: the same budget (NP, G) with :data:`TUNED_DE`'s ``f0`` and ``cr``. ``f0`` and
    ``cr`` only reach the optimisers that take them (the two DEs); any other preset is a
    ConfigError.
    """
    if not isinstance(preset, str) or preset not in PRESETS:
        raise ConfigError("preset", preset, " or ".join(PRESETS))
    out: dict[str, Any] = {
        "popsize": planner.population,
        "maxiter": planner.generations,
        "f0": planner.f0,
        "cr": planner.cr,
    }
    if preset == "tuned":
        out.update(TUNED_DE)
    return out


def run_optimizer(
    name: str, func: Objective, bounds, *, planner=None, **kwargs: Any
) -> OptimizeResult:
    """Run optimiser ``name`` with a scenario's ``planner`` settings as defaults.

    ``planner`` (a :class:`~poc_env.config.PlannerConfig`) supplies ``popsize``
    (``population``), ``maxiter`` (``generations``) and, for the optimisers that have them,
    ``f0`` and ``cr``; explicit keyword arguments win. An argument the optimiser does not take
    is a ConfigError (nothing is silently ignored).
    """
    fn = get_optimizer(name)
    params = inspect.signature(fn).parameters
    args: dict[str, Any] = {}
    if planner is not None:
        args.update(popsize=planner.population, maxiter=planner.generations)
        for key in ("f0", "cr"):
            if key in params:
                args[key] = getattr(planner, key)
    args.update(kwargs)
    unknown = sorted(set(args) - set(params))
    if unknown:
        raise ConfigError(
            f"{name}.{unknown[0]}", args[unknown[0]], "one of " + ", ".join(list(params)[2:])
        )
    return fn(func, bounds, **args)
