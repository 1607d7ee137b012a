"""The methods: each config class, the module that implements it, and the one method list.

A method is one module (config, named state, hooks); adding one touches that
module and the table below, nothing else. Dispatch (:mod:`learning.hooks`) is
generated from :data:`FAMILY_OF_CONFIG`: a compiled call on a state goes to the
module whose ``State`` it is.
"""

from __future__ import annotations

from types import ModuleType

from learning import (
    dyna_q,
    haql,
    pfh_rl,
    q_lambda,
    q_learning,
    rn_ql,
    rnh_ql,
    rnh_ql_plus,
    rnh_ql_plus_ablation,
    sarsa_rs,
)
from learning.config import MethodConfig
from learning.dyna_q import DynaQ
from learning.haql import HAQL
from learning.pfh_rl import PFHRL
from learning.q_lambda import QLambda
from learning.q_learning import STQL, QOpt
from learning.rn_ql import RNQL
from learning.rnh_ql import RNHQL
from learning.rnh_ql_plus import RNHQLPlus
from learning.rnh_ql_plus_ablation import RNHQLPlusAblation
from learning.sarsa_rs import SarsaRS

# in the order every table and figure lists them
FAMILY_OF_CONFIG: dict[type[MethodConfig], ModuleType] = {
    STQL: q_learning, RNQL: rn_ql, PFHRL: pfh_rl, SarsaRS: sarsa_rs, HAQL: haql,
    RNHQL: rnh_ql, QOpt: q_learning, QLambda: q_lambda, DynaQ: dyna_q,
    RNHQLPlus: rnh_ql_plus, RNHQLPlusAblation: rnh_ql_plus_ablation,
}
METHODS: dict[str, type[MethodConfig]] = {c.cli: c for c in FAMILY_OF_CONFIG}
FAMILY_OF_STATE: dict[type, ModuleType] = {m.State: m for m in FAMILY_OF_CONFIG.values()}


def family_of(cfg: MethodConfig) -> ModuleType:
    """The module that implements ``cfg``'s method."""
    try:
        return FAMILY_OF_CONFIG[type(cfg)]
    except KeyError:
        raise ValueError(f"{type(cfg).__name__} is not a registered method; known: "
                         f"{', '.join(METHODS)}") from None


def family_of_state(st) -> ModuleType:
    return FAMILY_OF_STATE[type(st)]


def n_states_of(st) -> int:
    """States the learner ``st`` was built for."""
    fam = family_of_state(st)
    return fam.n_states(st) if hasattr(fam, "n_states") else int(st.q.shape[0])


def config_from_fields(cli: str, fields: dict[str, object]) -> MethodConfig:
    """Rebuild a config from its CLI name and field values (e.g. from a checkpoint)."""
    if cli not in METHODS:
        raise ValueError(f"unknown method {cli!r}; known: {', '.join(METHODS)}")
    return METHODS[cli].from_fields(fields)
