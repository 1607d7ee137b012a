"""The RNH-QL+ ablation's named state and a fresh agent's: rnh-ql+'s, and the arrays of
the network potentials, re-based rows, Q traces and features."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from learning.geometry import Geometry
from learning.methods.rnh_ql_plus.optimism import Optimism, new_optimism
from learning.methods.rnh_ql_plus_ablation.config import Params, RNHQLPlusAblation
from learning.methods.rnh_ql_plus_ablation.features import Features, new_features
from learning.parts.free_space import FreeSpace, new_free_space
from learning.parts.known_routes import KnownRoutes, new_known_routes
from learning.parts.move_model import MoveModel, new_move_model
from learning.parts.move_reading import MoveReading, new_move_reading
from learning.parts.priority_queue import PairQueue, new_pair_queue
from learning.parts.tally import Tally, new_tally
from learning.parts.traces import QTraces, new_traces


class State(NamedTuple):
    par: Params
    tally: Tally
    q: np.ndarray  # float64[nS, nA]
    w: np.ndarray  # float64[K]; V_NN weights (network potentials)
    v_trace: np.ndarray  # float64[K]; their TD(lambda) traces (TD_REWARDS)
    phi_row: np.ndarray  # float64[nS]; the Phi each row's tried actions are based on (rebase;
    # empty without)
    feat: Features  # sparse features and leak-free supports
    model: MoveModel  # the moves seen, what planning replays
    free: FreeSpace  # the optimistic model: moves believed blocked, distances to G
    opt: Optimism  # the optimistic values y(s)
    traces: QTraces  # Q-table traces (lam_q > 0; empty without)
    values: np.ndarray  # float64[1, nA]; scratch: one row's action values (look-ahead)
    step_v: np.ndarray  # float64[1]; V_NN step, beta / mean |phi|^2 (derived)
    phi_here: np.ndarray  # float64[1]; Phi cached when the current state was entered
    shaping: np.ndarray  # bool[1]; shaping on this episode
    train_v: np.ndarray  # bool[1]; V_NN learns this episode
    known: KnownRoutes  # routes over moves seen to work (the greedy test's, known_route)
    sweep: PairQueue  # pairs queued for planned updates (sweeping; empty without)
    reading: MoveReading  # the rewards of a stay and of a clean arrival (bumps from rewards)


DERIVED = ("feat.base", "feat.centre", "step_v", "known.distance", "known.queue", "known.stale",
           "free.neighbour")
# Added to the state after checkpoints were written: a file without them loads the fresh
# values (no reward seen), and the agent relearns both at its next stay and clean arrival;
# until then every arrival counts as clean, the rule the file was trained under.
ADDED = ("reading.r_stay", "reading.r_clean")


def init_state(cfg: RNHQLPlusAblation, geom: Geometry, rng: np.random.Generator) -> State:
    n_s, n_a = geom.n_states, geom.n_actions
    feat = new_features(cfg, geom)
    n_c = int(feat.anchor.shape[0])
    step_v = (cfg.beta / float(np.mean(np.sum(feat.base * feat.base, axis=1)))
              if n_c else 0.0)  # no features: no V_NN to step
    # arrays a configuration never reads stay empty (a 512² checkpoint: 94 -> ~40 MB)
    n_rows = n_s if cfg.rebase else 0
    n_traced = n_s if cfg.lam_q > 0.0 else 0
    return State(cfg.params(), new_tally(), np.zeros((n_s, n_a)), np.zeros(n_c), np.zeros(n_c),
                 np.zeros(n_rows), feat, new_move_model(n_s, n_a), new_free_space(geom),
                 new_optimism(n_s), new_traces(n_traced, n_a), np.zeros((1, n_a)),
                 np.array([step_v]), np.zeros(1), np.zeros(1, np.bool_), np.zeros(1, np.bool_),
                 new_known_routes(n_s),
                 new_pair_queue(n_s * n_a) if cfg.sweeping else new_pair_queue(0, 0),
                 new_move_reading())
