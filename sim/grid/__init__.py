"""The gridded route world: rasterising a scenario, its tabular model, planners, the env.

``model`` (:class:`TabularModel`, :func:`build_model`) is the seam the learners train
on; ``raster`` decides which cells and moves are free, ``discretiser`` maps poses to
cells, ``planning`` holds the exact planners (the one BFS), ``actions`` the action
table and ``env`` the ``rnhql/GridRoute-v0`` gymnasium env.
"""

from sim.grid.actions import ACTION_DELTAS, ACTION_NAMES
from sim.grid.model import TabularModel, build_model

__all__ = ["ACTION_DELTAS", "ACTION_NAMES", "TabularModel", "build_model"]
