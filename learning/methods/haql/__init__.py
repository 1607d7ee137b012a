"""HAQL (``haql``, Bianchi 2008): heuristically accelerated Q-learning with a heuristic from
exploration.

``rules`` (the config, named state, the heuristic's upkeep and the hooks), ``least_bumped``
(the least-bumped route costs a cut-off state's heuristic follows, kept move by move).
"""

from __future__ import annotations

from learning.methods.haql.rules import (
    ADDED,
    COUNT_CAP,
    HAQL,
    Params,
    State,
    act,
    begin,
    exploit,
    heuristic_actions,
    init_state,
    observe,
    rederive,
    rederive_after_unblock,
    rederive_after_wall,
    rederive_cut,
    rederive_kept,
    update,
)

__all__ = ["ADDED", "COUNT_CAP", "HAQL", "Params", "State", "act", "begin", "exploit",
           "heuristic_actions", "init_state", "observe", "rederive", "rederive_after_unblock",
           "rederive_after_wall", "rederive_cut", "rederive_kept", "update"]
