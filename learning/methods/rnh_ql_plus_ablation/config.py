"""The RNH-QL+ ablation's config: rnh-ql+ with every switch the ablation turned, so a variant
is ``--set field=value``."""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum
from typing import ClassVar, NamedTuple

from learning.config import MethodConfig
from learning.methods.rnh_ql_plus import RNHQLPlus


class Potential(IntEnum):
    """Where the potential comes from (the ``v_target`` field)."""

    TD_REWARDS = 0  # the paper's: V_NN by TD(lambda) on the env rewards
    TABLE = 1  # V_NN regressed toward the table's own max_a Q(s, .) + Phi(s)
    LOG_TABLE = 2  # ... toward its log (Phi = exp V_NN)
    LOG_OPTIMISTIC = 3  # ... toward the log of the optimistic model's value y(s)
    OPTIMISTIC = 4  # Phi = y(s) itself, no network (the default: rnh-ql+)
    RESIDUAL = 5  # Phi = y * exp(V_NN), V_NN learning log(max_a Q + Phi over y)


@dataclass(frozen=True)
class RNHQLPlusAblation(RNHQLPlus):
    """The RNH-QL+ ablation: :class:`~learning.methods.rnh_ql_plus.RNHQLPlus`'s fields and the
    switches the ablation measured (README), each a field; with every switch at its default
    it is rnh-ql+ run for run. Rules in :mod:`learning.methods.rnh_ql_plus_ablation.rules`.

    With ``spacing=0, cutoff=0, v_target=0, warmup_episodes=300, shaping_scale=1, rebase=0,
    n_planning=0, lookahead=0`` it is the paper's RNH-QL (dense 10 x 10 lattice, TD(lambda)
    on rewards, no planning).

    * ``v_target``: where the potential comes from. 0: V_NN by TD(lambda) on the env
      rewards (the paper); 1: V_NN regressed (normalised LMS) toward the table's own
      max_a Q(s, .) + Phi(s); 2: the log of that; 3: V_NN regressed toward the log of
      the optimistic model's value y(s), at s and ``n_fit`` random states per step;
      **4 (default): Phi = y itself, no network** (rnh-ql+'s); 5: Phi = y * exp(V_NN),
      V_NN learning log(max_a Q + Phi over y), at most 0.
    * ``spacing``: centres every ``spacing`` cells (a lattice tied to the map
      size, centred on it), width ``sigma * spacing`` cells; ``cutoff`` makes
      the features sparse (the hot loop touches ~13-20 weights, not K).
    * ``leak_free=1``: a centre's feature is 0 at a cell not connected to the
      centre's anchor cell (the first visited cell nearest the centre) by moves
      the agent has seen succeed, staying within the support window: the
      potential cannot leak through walls the agent has not walked round.
    * ``lam_q``: Watkins Q(lambda) in the Q-table (0: one-step Q-learning).
    * ``rebase=1``: when Phi(s) changes, the tried actions of row s are re-based
      (Q(s, a) += Phi_old(s) - Phi_new(s)) so what was learned is never moved by
      the potential drifting; the potential then values only the actions not
      tried yet (Wiewiora 2003: shaping = initialising Q with Phi). Off by default:
      values learned while the optimistic model was too optimistic would stay
      inflated after it learns of a wall (measured: no route on zigzag-50).
    * ``sweeping=1`` needs ``v_target=4`` and no ``rebase`` (its priorities read Phi as
      the optimistic value).
    """

    name: ClassVar[str] = "RNH-QL+ ablation"
    cli: ClassVar[str] = "rnh-ql+ablation"
    # rnh-ql+'s options its rules do not have (refused at any value but the default)
    IGNORED: ClassVar[tuple[str, ...]] = ("model_acting", "model_test", "explore_steps")
    spacing: int = 4  # RBF centre spacing [cells]; 0: the paper's k x k lattice over the arena
    k: int = 10  # centres per axis when spacing = 0
    sigma: float = 1.0  # Gaussian width [lattice spacings]
    cutoff: float = 2.0  # feature support radius [widths]; 0: no cut-off (dense)
    normalise: int = 0  # 1: normalised RBF (a cell's features sum to 1)
    leak_free: int = 0  # 1: features limited to cells connected to the centre by seen moves
    # V_NN target: 0 TD(lambda) on rewards, 1 max_a Q(s,.) + Phi(s), 2 its log, 3 the log of
    # the optimistic model's value (learning.methods.rnh_ql_plus.optimism); 4: Phi = that
    # value, no network
    v_target: int = 4
    lam: float = 0.85  # V_NN trace decay lambda (v_target = 0)
    beta: float = 0.1  # V_NN step per unit of mean squared feature norm
    freeze_after_episodes: int | None = None  # stop training V_NN from this episode (None: never)
    lam_q: float = 0.0  # Q-table trace decay (Watkins Q(lambda), replacing); 0: Q-learning
    trace_min: float = 1e-8  # Q traces below this are dropped
    rebase: int = 0  # 1: re-base a row's tried actions when Phi(s) changes (see above)
    n_fit: int = 0  # v_target = 3: extra V_NN fits at random states per real step [fits]

    def __post_init__(self) -> None:
        MethodConfig.__post_init__(self)  # rnh-ql+'s gamma < 1 holds here only from v_target 3
        if self.v_target >= 3 and self.gamma >= 1.0:
            raise ValueError(f"RNHQLPlusAblation.gamma = {self.gamma!r} must be < 1 with "
                             f"v_target = {self.v_target} (the optimistic model's value "
                             "discounts: use v_target 0-2 for gamma = 1)")
        if self.sweeping and (self.v_target != Potential.OPTIMISTIC or self.rebase):
            raise ValueError(f"RNHQLPlusAblation.sweeping = {self.sweeping!r} needs v_target "
                             "= 4 and rebase = 0 (its priorities read Phi as the optimistic "
                             "value): set sweeping = 0 or use those settings")

    @property
    def uses_features(self) -> bool:
        """Whether anything reads the RBF features and V_NN's weights: a network potential
        (``v_target`` < 4) or leak-free supports. Phi = the optimistic value keeps them
        empty."""
        return self.v_target != Potential.OPTIMISTIC or bool(self.leak_free)

    def params(self) -> Params:
        """The compiled rules' scalars (every path compiled: a switch is a branch)."""
        freeze = math.inf if self.freeze_after_episodes is None else self.freeze_after_episodes
        return Params(
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
