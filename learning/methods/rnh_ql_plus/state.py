"""RNH-QL+'s named state and a fresh agent's."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from learning.geometry import Geometry
from learning.methods.rnh_ql_plus.config import Params, RNHQLPlus
from learning.methods.rnh_ql_plus.optimism import Optimism, new_optimism
from learning.parts.coverage import Coverage, new_coverage, walk_budget
from learning.parts.free_space import FreeSpace, new_free_space
from learning.parts.known_routes import KnownRoutes, new_known_routes
from learning.parts.move_model import MoveModel, new_move_model
from learning.parts.move_reading import MoveReading, new_move_reading
from learning.parts.priority_queue import PairQueue, new_pair_queue
from learning.parts.tally import Tally, new_tally


class State(NamedTuple):
    par: Params
    tally: Tally
    q: np.ndarray  # float64[nS, nA]
    model: MoveModel  # the moves seen, what planning replays
    free: FreeSpace  # the optimistic model: moves believed blocked, distances to G
    opt: Optimism  # the optimistic values y(s)
    values: np.ndarray  # float64[1, nA]; scratch: one row's action values (look-ahead)
    phi_here: np.ndarray  # float64[1]; Phi cached when the current state was entered
    shaping: np.ndarray  # bool[1]; shaping on this episode
    known: KnownRoutes  # routes over moves seen to work (the greedy test's, known_route)
    sweep: PairQueue  # pairs queued for planned updates (sweeping; empty without)
    reading: MoveReading  # the rewards of a stay and of a clean arrival (bumps from rewards)
    coverage: Coverage  # the coverage walk's field and scratch (explore_steps)


# The coverage walk's scratch is derived; its field (``coverage.distance``) is stored: the
# walk goes down it while it is fresh, and a rebuilt field can send a resumed walk along
# another of the equally short ways (a resumed run would not be the uninterrupted one).
# ``coverage.done`` re-derives itself at the walk's next step, drawing no random number.
DERIVED = ("known.distance", "known.queue", "known.stale", "free.neighbour",
           "coverage.queue", "coverage.mark", "coverage.first", "coverage.searches",
           "coverage.left", "coverage.done")
# Added to the state after checkpoints were written: a file without them loads the fresh
# values (no reward seen), and the agent relearns both at its next stay and clean arrival;
# until then every arrival counts as clean, the rule the file was trained under. A file
# without the coverage field was written without the walk, or before the field was stored.
ADDED = ("reading.r_stay", "reading.r_clean", "coverage.distance")


def init_state(cfg: RNHQLPlus, geom: Geometry, rng: np.random.Generator) -> State:
    n_s, n_a = geom.n_states, geom.n_actions
    par = cfg.params()._replace(explore_steps=walk_budget(cfg.explore_steps, geom))
    q = np.full((n_s, n_a), float(cfg.untried_bonus))  # optimism in the face of the untried
    return State(par, new_tally(), q, new_move_model(n_s, n_a),
                 new_free_space(geom), new_optimism(n_s), np.zeros((1, n_a)), np.zeros(1),
                 np.zeros(1, np.bool_), new_known_routes(n_s),
                 new_pair_queue(n_s * n_a) if cfg.sweeping else new_pair_queue(0, 0),
                 new_move_reading(), new_coverage(n_s))
