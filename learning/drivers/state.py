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


__all__ = ["copy_state", "init_state"]
