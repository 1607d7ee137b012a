"""A fresh learner of any method: its module's named state, built from a config, a geometry
and a generator (only RN-QL draws from it here, its initial net weights)."""

from __future__ import annotations

import numpy as np

from learning.compiled.named_state import copy_state
from learning.config import MethodConfig
from learning.geometry import Geometry
from learning.methods.registry import family_of


def init_state(cfg: MethodConfig, geom: Geometry, rng: np.random.Generator):
    return family_of(cfg).init_state(cfg, geom, rng)


def carried_state(cfg: MethodConfig, st):
    """A learner's state as it starts its next world (a physics rung after the grid, or a
    higher rung after a lower one): a copy of the whole state (tables, model, potential,
    counts) with the parameters of ``cfg`` (the new phase's config), passed through its
    method's ``carry`` hook when the method defines one (a multi-fidelity method marks
    what it knew below). Traces and per-episode scratch are reset by the method's
    ``begin`` at the first episode, as within one world."""
    st = copy_state(st)
    if hasattr(st, "par"):
        st = st._replace(par=cfg.params())
    carry = getattr(family_of(cfg), "carry", None)
    return st if carry is None else carry(st)


__all__ = ["carried_state", "copy_state", "init_state"]
