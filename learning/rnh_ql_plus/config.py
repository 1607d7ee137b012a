"""RNH-QL+'s config: every ingredient is a field, so an ablation is ``--set field=value``."""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum
from typing import ClassVar, NamedTuple

from learning.config import MethodConfig


class Potential(IntEnum):
    """Where the potential comes from (the ``v_target`` field)."""

    TD_REWARDS = 0  # the paper's: V_NN by TD(lambda) on the env rewards
    TABLE = 1  # V_NN regressed toward the table's own max_a Q(s, .) + Phi(s)
    LOG_TABLE = 2  # ... toward its log (Phi = exp V_NN)
    LOG_OPTIMISTIC = 3  # ... toward the log of the optimistic model's value y(s)
    OPTIMISTIC = 4  # Phi = y(s) itself, no network (the default)
    RESIDUAL = 5  # Phi = y * exp(V_NN), V_NN learning log(max_a Q + Phi over y)


@dataclass(frozen=True)
class RNHQLPlus(MethodConfig):
    """RNH-QL+: RNH-QL's two layers (Q-table below, a potential shaping it above), fixed
    where the ablation's measurements show it breaking. Rules in :mod:`learning.rnh_ql_plus.rules`.

    Every ingredient is a field, so an ablation is ``--set field=value``; with
    ``spacing=0, cutoff=0, v_target=0, warmup_episodes=300, shaping_scale=1, rebase=0,
    n_planning=0, lookahead=0`` it is the paper's RNH-QL (dense 10 x 10 lattice, TD(lambda)
    on rewards, no planning); with ``shaping_scale=0, lookahead=0`` it is Dyna-Q (bit for
    bit).

    * ``v_target``: where the potential comes from. 0: V_NN by TD(lambda) on the env
      rewards (the paper); 1: V_NN regressed (normalised LMS) toward the table's own
      max_a Q(s, .) + Phi(s); 2: the log of that; 3: V_NN regressed toward the log of
      the optimistic model's value y(s) (:mod:`learning.rnh_ql_plus.optimism`: the value of the
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
    * ``sweeping=1``: prioritized sweeping (Moore & Atkeson 1993) of the planned updates:
      after a real step the seen pairs leading into s are queued by their TD error
      relative to the optimistic value of their state, and the ``n_planning`` updates
      take the largest first (each queueing its own predecessors); uniform replays fill
      the budget when the queue runs dry. Needs Phi = the optimistic value
      (``v_target=4``, no ``rebase``).
    * ``known_route=1`` (default): the greedy test (never the behaviour) follows, from a
      cell with one, the shortest route over moves seen to work
      (:mod:`learning.known_routes`); elsewhere the greedy choice above. The moves seen
      to work only grow, so once the optimal route is walked the test stays optimal.
    """

    name: ClassVar[str] = "RNH-QL+"
    cli: ClassVar[str] = "rnh-ql+"
    spacing: int = 4  # RBF centre spacing [cells]; 0: the paper's k x k lattice over the arena
    k: int = 10  # centres per axis when spacing = 0
    sigma: float = 1.0  # Gaussian width [lattice spacings]
    cutoff: float = 2.0  # feature support radius [widths]; 0: no cut-off (dense)
    normalise: int = 0  # 1: normalised RBF (a cell's features sum to 1)
    leak_free: int = 0  # 1: features limited to cells connected to the centre by seen moves
    # V_NN target: 0 TD(lambda) on rewards, 1 max_a Q(s,.) + Phi(s), 2 its log, 3 the log of
    # the optimistic model's value (learning.rnh_ql_plus.optimism); 4: Phi = that value, no network
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
    known_route: int = 1  # 1: the greedy test follows the shortest route of moves seen to work
    sweeping: int = 0  # 1: planned updates go to the pairs whose values changed most first

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.v_target >= 3 and self.gamma >= 1.0:
            raise ValueError(f"RNHQLPlus.gamma = {self.gamma!r} must be < 1 with v_target = "
                             f"{self.v_target} (the optimistic model's value discounts: "
                             "use v_target 0-2 for gamma = 1)")
        if self.sweeping and (self.v_target != Potential.OPTIMISTIC or self.rebase):
            raise ValueError(f"RNHQLPlus.sweeping = {self.sweeping!r} needs v_target = 4 and "
                             "rebase = 0 (its priorities read Phi as the optimistic value): "
                             "set sweeping = 0 or use those settings")

    @property
    def uses_features(self) -> bool:
        """Whether anything reads the RBF features and V_NN's weights: a network potential
        (``v_target`` < 4) or leak-free supports. The default (Phi = the optimistic value)
        keeps them empty."""
        return self.v_target != Potential.OPTIMISTIC or bool(self.leak_free)

    def params(self) -> Params | LeanParams:
        """The compiled rules' scalars. :class:`LeanParams` (same fields) when the potential
        is the optimistic value and leak-free supports, re-basing and Q traces are off: the
        kernel is then compiled without those paths (see
        :func:`learning.rnh_ql_plus.rules.lean`)."""
        freeze = math.inf if self.freeze_after_episodes is None else self.freeze_after_episodes
        lean = (self.v_target == Potential.OPTIMISTIC and not self.leak_free and not self.rebase
                and self.lam_q == 0.0)
        return (LeanParams if lean else Params)(
            float(self.eps), float(self.alpha), float(self.gamma), float(self.lam),
            float(self.warmup_episodes), float(freeze), int(self.n_planning),
            int(self.v_target), float(self.shaping_scale), float(self.lam_q),
            float(self.trace_min), bool(self.normalise), bool(self.leak_free),
            bool(self.rebase), bool(self.lookahead), int(self.n_fit), bool(self.known_route),
            bool(self.sweeping))



class Params(NamedTuple):
    eps: float
    alpha: float
    gamma: float
    lam: float  # V_NN trace decay (TD_REWARDS)
    warmup: float  # shaping from this episode on
    freeze: float  # V_NN trained before this episode (inf: always)
    n_planning: int
    v_target: int  # a Potential
    scale: float  # shaping_scale
    lam_q: float
    trace_min: float
    normalise: bool
    leak_free: bool
    rebase: bool
    lookahead: bool
    n_fit: int
    known_route: bool
    sweeping: bool


# The same fields; a state holding these compiles the lean kernel (see RNHQLPlus.params).
LeanParams = NamedTuple("LeanParams", list(Params.__annotations__.items()))
