"""The agent state: one fixed tuple of arrays for every method (what kernels mutate and
checkpoints store), and its initialisation from a config, a geometry and a generator.

Slots unused by a method are empty arrays. Per rule family:

==========  ==================  =====================  ============================
slot        RNH-QL              RN-QL                  others
==========  ==================  =====================  ============================
q           Q-table [nS, nA]    [0, nA] (unused)       Q-table [nS, nA]
w           RBF weights [K]     net weights [4(4H+1)]  SARSA-RS: abstract V [n_z]
e           RBF traces [K]      net traces             --
feat        phi [nS, K]         inputs in [0,1]^2      PFH-RL: Phi [nS, 1]
imap        --                  --                     HAQL pi_H, bumps [nS, 9]; SARSA-RS z [nS, 1];
                                                       Dyna-Q model s', done [nS, 2nA]
fmap        --                  scratch row [1, nA]    Dyna-Q model reward [nS, nA];
                                                       Q(lambda): Q traces [nS, nA]
ilist       --                  --                     Q(lambda) touched pairs,
                                                       Dyna-Q seen pairs [nS*nA] and
                                                       outcome counts [2nS*nA]
==========  ==================  =====================  ============================

``ivar``/``fvar``/``par`` hold scalars, named in :mod:`learning.kinds`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from learning import kinds as K
from learning import mlp, rbf, shaping
from learning.geometry import Geometry
from learning.methods import MethodConfig

RNQL_HIDDEN = 10  # the paper's 2-10-1 nets


class AgentState(NamedTuple):
    ivar: np.ndarray  # int64[N_IVAR]
    fvar: np.ndarray  # float64[N_FVAR]
    par: np.ndarray  # float64[N_PARAMS]; the packed config
    q: np.ndarray  # float64[nS, nA]
    w: np.ndarray  # float64[:]
    e: np.ndarray  # float64[:]
    feat: np.ndarray  # float64[nS, :]
    imap: np.ndarray  # int32[nS, :]
    fmap: np.ndarray  # float64[:, nA]
    ilist: np.ndarray  # int32[:]


def _f(*shape: int) -> np.ndarray:
    return np.zeros(shape, dtype=np.float64)


def _i(*shape: int) -> np.ndarray:
    return np.zeros(shape, dtype=np.int32)


def init_state(cfg: MethodConfig, geom: Geometry, rng: np.random.Generator) -> AgentState:
    """A fresh agent. Only RN-QL draws from ``rng`` here (its initial net weights)."""
    n_s, n_a = geom.n_states, geom.n_actions
    kind = cfg.kind
    ivar = np.zeros(K.N_IVAR, dtype=np.int64)
    ivar[K.I_KIND] = kind
    ivar[K.I_PENDING] = -1
    fvar = _f(K.N_FVAR)
    fvar[K.F_GK] = 1.0
    q, w, e, feat = _f(n_s, n_a), _f(0), _f(0), _f(n_s, 0)
    imap, fmap, ilist = _i(n_s, 0), _f(0, n_a), _i(0)
    if kind == K.QL:
        q[:] = cfg.q0
    elif kind == K.QLAMBDA:
        fmap, ilist = _f(n_s, n_a), _i(n_s * n_a)
    elif kind == K.RNQL:
        q = _f(0, n_a)
        w = mlp.init_weights(n_a, RNQL_HIDDEN, cfg.init_range, rng)
        e = np.zeros_like(w)
        feat = mlp.normalised_inputs(geom.coords, geom.bounds_m)
        fmap = _f(1, n_a)
    elif kind == K.PFH:
        feat = shaping.pfh_potential(geom, cfg.scale)
    elif kind == K.SARSARS:
        imap, n_z = shaping.abstract_states(geom, cfg.block)
        w = _f(n_z)
    elif kind == K.HAQL:
        from learning.explored import init_explored

        imap, ilist = init_explored(geom, bool(cfg.explored))
        if not cfg.explored:
            imap[:, 0] = shaping.heuristic_actions(geom)[:, 0]
    elif kind == K.DYNA:
        imap = np.full((n_s, 2 * n_a), -1, dtype=np.int32)
        imap[:, n_a:] = 0
        fmap, ilist = _f(n_s, n_a), _i(3 * n_s * n_a)  # seen pairs, outcome counts
    elif kind == K.RNHQL:
        feat = rbf.rbf_features(geom.coords, geom.bounds_m,
                                *rbf.lattice_size(geom.bounds_m, cfg.k, cfg.spacing_m))
        w, e = _f(feat.shape[1]), _f(feat.shape[1])
        fvar[K.F_STEP_V] = cfg.beta / float(np.mean(np.sum(feat * feat, axis=1)))
    elif kind == K.RNHQLP:  # RNH-QL+: layout in learning.rules_plus
        from learning.plus_features import init_plus

        sl = init_plus(cfg, geom)
        q, w, e, feat = sl["q"], sl["w"], sl["e"], sl["feat"]
        imap, fmap, ilist = sl["imap"], sl["fmap"], sl["ilist"]
        fvar[K.F_STEP_V] = sl["step_v"]
        ivar[K.I_GOAL] = sl["goal"]
    else:
        raise ValueError(f"{type(cfg).__name__} has unknown rule family {kind}")
    return AgentState(ivar=ivar, fvar=fvar, par=cfg.params(), q=q, w=w, e=e,
                      feat=np.ascontiguousarray(feat), imap=imap, fmap=fmap, ilist=ilist)


def copy_state(st: AgentState) -> AgentState:
    return AgentState(*(a.copy() for a in st))
