"""The learning methods as frozen config dataclasses (paper defaults) and their registry.

A config is pure data: which update rule (``kind``, one of :mod:`learning.kinds`)
and its hyper-parameters with units/meaning in the field comments. The rules
themselves live in the njit modules (:mod:`learning.rules`, :mod:`learning.rbf`,
:mod:`learning.mlp`, :mod:`learning.shaping`), shared by both drivers.
``params()`` packs the fields into the float64 vector those rules read, with the
slot layout documented in :mod:`learning.kinds`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from learning import kinds as K

# field -> (valid?, what a valid value is); checked for every config that has the field
_VALID = {
    "eps": (lambda v: 0.0 <= v <= 1.0, "in [0, 1]"),
    "alpha": (lambda v: 0.0 < v <= 1.0, "in (0, 1]"),
    "gamma": (lambda v: 0.0 < v <= 1.0, "in (0, 1]"),
    "lam": (lambda v: 0.0 <= v <= 1.0, "in [0, 1]"),
    "k": (lambda v: v >= 1, ">= 1"),
    "spacing_m": (lambda v: v >= 0.0, ">= 0 (0: k x k centres)"),
    "block": (lambda v: v >= 1, ">= 1"),
    "n_planning": (lambda v: v >= 0, ">= 0"),
    "warmup_episodes": (lambda v: v >= 0, ">= 0"),
    "freeze_after_episodes": (lambda v: v >= 0, ">= 0 or None"),
    "beta": (lambda v: v > 0.0, "> 0"),
    "alpha_v": (lambda v: 0.0 < v <= 1.0, "in (0, 1]"),
    "q_scale": (lambda v: v > 0.0, "> 0"),
    "trace_min": (lambda v: v > 0.0, "> 0"),
    "init_range": (lambda v: v > 0.0, "> 0"),
    "spacing": (lambda v: v >= 0, ">= 0"),
    "sigma": (lambda v: v > 0.0, "> 0"),
    "cutoff": (lambda v: v >= 0.0, ">= 0 (0: no cut-off)"),
    "normalise": (lambda v: v in (0, 1), "0 or 1"),
    "v_target": (lambda v: v in (0, 1, 2, 3, 4, 5), "0 (TD on rewards), 1 (max_a Q + Phi), 2 "
                 "(its log), 3 (log of the optimistic model's value), 4 (that value, no "
                 "network), 5 (log of max_a Q + Phi over that value)"),
    "shaping_scale": (lambda v: v >= 0.0, ">= 0"),
    "lam_q": (lambda v: 0.0 <= v <= 1.0, "in [0, 1]"),
    "leak_free": (lambda v: v in (0, 1), "0 or 1"),
    "rebase": (lambda v: v in (0, 1), "0 or 1"),
    "lookahead": (lambda v: v in (0, 1), "0 or 1"),
    "n_fit": (lambda v: v >= 0, ">= 0"),
}


@dataclass(frozen=True)
class MethodConfig:
    """Fields every method has. Episodes are 0-based; rewards are the env's."""

    name: ClassVar[str] = "?"  # paper/display name
    cli: ClassVar[str] = "?"  # CLI name, the key in METHODS
    kind: ClassVar[int] = -1  # update-rule family, see learning.kinds

    eps: float = 0.1  # probability of a uniformly random action (epsilon-greedy)
    alpha: float = 0.1  # Q learning rate (step size on the TD error)
    gamma: float = 0.95  # discount per step

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            if f.name in _VALID:
                ok, what = _VALID[f.name]
                v = getattr(self, f.name)
                if v is not None and not ok(v):
                    raise ValueError(f"{type(self).__name__}.{f.name} = {v!r} must be {what}")

    def extra(self) -> tuple[float, ...]:
        """Method-specific params, in the slot order of learning.kinds (from slot 4)."""
        return ()

    def params(self) -> np.ndarray:
        """float64[N_PARAMS]: the packed hyper-parameters the njit rules read."""
        p = np.zeros(K.N_PARAMS)
        p[K.P_EPS], p[K.P_ALPHA], p[K.P_GAMMA] = self.eps, self.alpha, self.gamma
        p[K.P_LAMBDA] = getattr(self, "lam", 0.0)
        ex = self.extra()
        p[K.P_X0:K.P_X0 + len(ex)] = ex
        return p

    def fields(self) -> dict[str, object]:
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}


@dataclass(frozen=True)
class STQL(MethodConfig):
    """Tabular Q-learning, Q0 = 0 (Watkins 1989)."""

    name: ClassVar[str] = "ST-QL"
    cli: ClassVar[str] = "st-ql"
    kind: ClassVar[int] = K.QL
    q0: float = 0.0  # initial Q for every (s, a) [reward units]

    def extra(self) -> tuple[float, ...]:
        return (self.q0,)


@dataclass(frozen=True)
class QOpt(STQL):
    """Q-learning with optimistic initial values: Q0 = the goal reward."""

    name: ClassVar[str] = "Q-OPT"
    cli: ClassVar[str] = "q-opt"
    q0: float = 100.0  # initial Q [reward units]; the paper's goal reward


@dataclass(frozen=True)
class QLambda(MethodConfig):
    """Tabular Watkins Q(lambda), replacing traces, cut when a non-greedy action is taken.

    Replacing (not accumulating) traces: a bump keeps the agent in its cell, and
    accumulating traces on such self-loops grow to 1/(1-gamma*lambda) ~ 5.
    """

    name: ClassVar[str] = "Q(lambda)"
    cli: ClassVar[str] = "q-lambda"
    kind: ClassVar[int] = K.QLAMBDA
    lam: float = 0.85  # trace decay lambda
    trace_min: float = 1e-8  # traces below this are dropped (keeps the trace list short)

    def extra(self) -> tuple[float, ...]:
        return (self.trace_min,)


@dataclass(frozen=True)
class RNQL(MethodConfig):
    """Q from four 2-10-1 sigmoid nets (one per action) over the normalised cell centre.

    Watkins Q(lambda) with gradient traces (accumulating), cut when the action
    taken is non-greedy. The nets predict Q / q_scale: with Q ~ 100 an unscaled
    linear output would need weights ~100, which makes the hidden-layer
    gradients ~100x larger and saturates the sigmoids.
    """

    name: ClassVar[str] = "RN-QL"
    cli: ClassVar[str] = "rn-ql"
    kind: ClassVar[int] = K.RNQL
    lam: float = 0.85  # trace decay lambda
    q_scale: float = 100.0  # Q = q_scale * net output [reward units]
    init_range: float = 0.5  # initial weights ~ U(-init_range, init_range)

    def extra(self) -> tuple[float, ...]:
        return (self.q_scale,)


@dataclass(frozen=True)
class PFHRL(MethodConfig):
    """Q-learning + static potential shaping (Ng 1999), Phi = -scale * Manhattan cells to G."""

    name: ClassVar[str] = "PFH-RL"
    cli: ClassVar[str] = "pfh-rl"
    kind: ClassVar[int] = K.PFH
    scale: float = 1.0  # potential per cell of Manhattan distance [reward units / cell]


@dataclass(frozen=True)
class SarsaRS(MethodConfig):
    """SARSA + shaping Phi = omega * V(z) from an abstract b x b-cell grid (Grzes & Kudenko 2008).

    V over abstract states is learned online by SMDP TD: when the abstract state
    changes z -> z' after k steps with discounted reward R,
    V(z) += alpha_v * (R + gamma^k V(z') - V(z)) (V(z') = 0 on termination).
    """

    name: ClassVar[str] = "SARSA-RS"
    cli: ClassVar[str] = "sarsa-rs"
    kind: ClassVar[int] = K.SARSARS
    block: int = 5  # abstract cell side b [cells]
    omega: float = 1.0  # potential scale omega [dimensionless]
    alpha_v: float = 0.1  # abstract-V learning rate

    def extra(self) -> tuple[float, ...]:
        return (self.omega, self.alpha_v)


@dataclass(frozen=True)
class HAQL(MethodConfig):
    """Heuristically accelerated Q-learning (Bianchi 2008): act on argmax[Q + xi * H^beta].

    H(s,a) = max_b Q(s,b) - Q(s,a) + eta for the heuristic move a = pi_H(s), else
    0; Q is learned off-policy. With xi = beta = 1 the heuristic move always wins
    the argmax, so what pi_H is decides everything:

    - ``explored = 1`` (default): pi_H is a heuristic from exploration
      (:mod:`learning.explored`): the first move of a shortest route to G over the
      moves not yet seen to fail, re-derived at every new bump. The route follows
      what the agent has learned about the walls.
    - ``explored = 0``: Bianchi's static heuristic, the move that most reduces
      the Manhattan distance to G. It never changes, so the route is fixed before
      learning starts (kept to show exactly that).
    """

    name: ClassVar[str] = "HAQL"
    cli: ClassVar[str] = "haql"
    kind: ClassVar[int] = K.HAQL
    xi: float = 1.0  # heuristic weight xi
    beta_h: float = 1.0  # heuristic exponent beta
    eta: float = 0.1  # margin of the heuristic move over the current max [reward units]
    explored: int = 1  # 1: heuristic from exploration; 0: the static Manhattan move

    def extra(self) -> tuple[float, ...]:
        return (self.xi, self.beta_h, self.eta, float(self.explored))


@dataclass(frozen=True)
class DynaQ(MethodConfig):
    """Dyna-Q (Sutton 1990): Q-learning + planning from a learned deterministic model."""

    name: ClassVar[str] = "DYNA-Q"
    cli: ClassVar[str] = "dyna-q"
    kind: ClassVar[int] = K.DYNA
    n_planning: int = 5  # simulated Q updates per real step, (s, a) uniform over seen pairs

    def extra(self) -> tuple[float, ...]:
        return (float(self.n_planning),)


@dataclass(frozen=True)
class RNHQL(MethodConfig):
    """RNH-QL: Q-table + Gaussian RBF network V_NN giving dynamic potential shaping.

    V_NN(s) = w . phi(s) over k x k Gaussian centres (cell-centred lattice over
    the arena, width = lattice spacing), trained by TD(lambda) from the first
    episode with traces cut on non-greedy actions (a non-greedy step leaves w
    unchanged). From episode ``warmup_episodes`` on, the Q update adds
    F = gamma * Phi(s') - Phi(s), Phi = V_NN evaluated when a state is entered
    (Devlin & Kudenko 2012), Phi(goal) = 0.

    The V_NN step is ``beta / mean_s |phi(s)|^2`` (normalised LMS): a constant, so
    this is plain linear TD(lambda), and with sigma = spacing |phi|^2 ~ pi, so
    beta = 0.1 moves V(s) by ~10% of the TD error per visit, ~50% with the
    trace's 1/(1 - gamma*lambda) ~ 5 revisits: stable.
    """

    name: ClassVar[str] = "RNH-QL"
    cli: ClassVar[str] = "rnh-ql"
    kind: ClassVar[int] = K.RNHQL
    lam: float = 0.85  # V_NN trace decay lambda
    k: int = 10  # RBF centres per axis (k * k in all), the paper's 10 x 10
    spacing_m: float = 0.0  # > 0: a centre every spacing_m metres per axis instead of k x k
    beta: float = 0.1  # V_NN step per unit of mean squared feature norm
    warmup_episodes: int = 300  # shaping starts at this 0-based episode index
    freeze_after_episodes: int | None = None  # stop training V_NN from this episode (None: never)

    def extra(self) -> tuple[float, ...]:
        freeze = math.inf if self.freeze_after_episodes is None else self.freeze_after_episodes
        return (self.beta, float(self.warmup_episodes), float(freeze))


@dataclass(frozen=True)
class RNHQLPlus(MethodConfig):
    """RNH-QL+: RNH-QL's two layers (Q-table below, a potential shaping it above), fixed
    where the ablation's measurements show it breaking. Rules in :mod:`learning.rules_plus`.

    Every ingredient is a field, so an ablation is ``--set field=value``; with
    ``spacing=0, cutoff=0, v_target=0, warmup_episodes=300, shaping_scale=1, rebase=0,
    n_planning=0, lookahead=0`` it is the paper's RNH-QL (dense 10 x 10 lattice, TD(lambda)
    on rewards, no planning); with ``shaping_scale=0, lookahead=0`` it is Dyna-Q (bit for
    bit).

    * ``v_target``: where the potential comes from. 0: V_NN by TD(lambda) on the env
      rewards (the paper); 1: V_NN regressed (normalised LMS) toward the table's own
      max_a Q(s, .) + Phi(s); 2: the log of that; 3: V_NN regressed toward the log of
      the optimistic model's value y(s) (:mod:`learning.plus_optimism`: the value of the
      shortest route to G over the moves not seen to fail), at s and ``n_fit`` random
      states per step; **4 (default): Phi = y itself, no network** (every network
      variant measured worse, see the README's ablation); 5: Phi = y * exp(V_NN), V_NN
      learning log(max_a Q + Phi over y), at most 0.
    * ``lookahead=1``: an untried action is valued by one step of look-ahead in the
      optimistic model, r_free + gamma * Phi(neighbour) - Phi(s) (Wiewiora's look-ahead
      advice), in acting and in the greedy test.
    * ``spacing``: centres every ``spacing`` cells (a lattice tied to the map
      size, centred on it), width ``sigma * spacing`` cells; ``cutoff`` makes
      the features sparse (the hot loop touches ~13-20 weights, not K).
    * ``leak_free=1``: a centre's feature is 0 at a cell not connected to the
      centre's anchor cell (the first visited cell nearest the centre) by moves
      the agent has seen succeed, staying within the support window: the
      potential cannot leak through walls the agent has not walked round.
    * ``n_planning``: Dyna-style Q updates per real step on seen (s, a) pairs
      of a learned deterministic model, each with the shaping term of the
      current potential.
    * ``lam_q``: Watkins Q(lambda) in the Q-table (0: one-step Q-learning).
    * ``rebase=1``: when Phi(s) changes, the tried actions of row s are re-based
      (Q(s, a) += Phi_old(s) - Phi_new(s)) so what was learned is never moved by
      the potential drifting; the potential then values only the actions not
      tried yet (Wiewiora 2003: shaping = initialising Q with Phi). Off by default:
      values learned while the optimistic model was too optimistic would stay
      inflated after it learns of a wall (measured: no route on zigzag-50).
    """

    name: ClassVar[str] = "RNH-QL+"
    cli: ClassVar[str] = "rnh-ql+"
    kind: ClassVar[int] = K.RNHQLP
    spacing: int = 4  # RBF centre spacing [cells]; 0: the paper's k x k lattice over the arena
    k: int = 10  # centres per axis when spacing = 0
    sigma: float = 1.0  # Gaussian width [lattice spacings]
    cutoff: float = 2.0  # feature support radius [widths]; 0: no cut-off (dense)
    normalise: int = 0  # 1: normalised RBF (a cell's features sum to 1)
    leak_free: int = 0  # 1: features limited to cells connected to the centre by seen moves
    # V_NN target: 0 TD(lambda) on rewards, 1 max_a Q(s,.) + Phi(s), 2 its log, 3 the log of
    # the optimistic model's value (learning.plus_optimism); 4: Phi = that value, no network
    v_target: int = 4
    lam: float = 0.85  # V_NN trace decay lambda (v_target = 0)
    beta: float = 0.1  # V_NN step per unit of mean squared feature norm
    warmup_episodes: int = 0  # shaping starts at this 0-based episode index
    freeze_after_episodes: int | None = None  # stop training V_NN from this episode (None: never)
    shaping_scale: float = 1.0  # Phi = shaping_scale * V_NN (or * y) [dimensionless]; 0: none
    n_planning: int = 10  # shaped model-based Q updates per real step [updates]
    lam_q: float = 0.0  # Q-table trace decay (Watkins Q(lambda), replacing); 0: Q-learning
    trace_min: float = 1e-8  # Q traces below this are dropped
    rebase: int = 0  # 1: re-base a row's tried actions when Phi(s) changes (see above)
    lookahead: int = 1  # 1: untried actions valued by one step of look-ahead on Phi
    n_fit: int = 0  # v_target = 3: extra V_NN fits at random states per real step [fits]

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.v_target >= 3 and self.gamma >= 1.0:
            raise ValueError(f"RNHQLPlus.gamma = {self.gamma!r} must be < 1 with v_target = "
                             f"{self.v_target} (the optimistic model's value discounts: "
                             "use v_target 0-2 for gamma = 1)")

    def extra(self) -> tuple[float, ...]:
        freeze = math.inf if self.freeze_after_episodes is None else self.freeze_after_episodes
        return (self.beta, float(self.warmup_episodes), float(freeze), float(self.n_planning),
                float(self.v_target), self.shaping_scale, self.lam_q, self.trace_min,
                float(self.normalise), float(self.leak_free), float(self.rebase),
                float(self.lookahead), float(self.n_fit))

    def params(self) -> np.ndarray:
        """float64[N_PARAMS_PLUS]: a longer vector than the other families (slots PP_*)."""
        p = np.zeros(K.N_PARAMS_PLUS)
        p[K.P_EPS], p[K.P_ALPHA], p[K.P_GAMMA] = self.eps, self.alpha, self.gamma
        p[K.P_LAMBDA] = self.lam
        ex = self.extra()
        p[K.P_X0:K.P_X0 + len(ex)] = ex
        return p


METHODS: dict[str, type[MethodConfig]] = {
    c.cli: c for c in (STQL, RNQL, PFHRL, SarsaRS, HAQL, RNHQL, QOpt, QLambda, DynaQ)
}
METHODS[RNHQLPlus.cli] = RNHQLPlus


def config_from_fields(cli: str, fields: dict[str, object]) -> MethodConfig:
    """Rebuild a config from its CLI name and field values (e.g. from a checkpoint)."""
    if cli not in METHODS:
        raise ValueError(f"unknown method {cli!r}; known: {', '.join(METHODS)}")
    return METHODS[cli](**fields)

