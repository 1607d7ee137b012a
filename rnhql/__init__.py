"""rnhql: route searching with RBF-network heuristic Q-learning, on a grid and on a physics
robot, recorded with Rerun. The package's face: one import for a scenario script.

>>> import rnhql                                                            # doctest: +SKIP
>>> cmp = rnhql.compare("paper-40", ["rnh-ql+", "haql"], seeds=3, episodes=300)  # doctest: +SKIP
>>> grid = rnhql.train("maze-1", "haql", episodes=300, seed=0)             # doctest: +SKIP
>>> robot = rnhql.train("maze-1", "haql", world="physics", fidelity="slip",
...                     episodes=100, seed=0, init=grid)                    # doctest: +SKIP

- :func:`train`, :func:`compare`, :func:`grade`, :func:`optimum`, :func:`route`,
  :func:`aliasing`, :func:`crosscheck`: the library calls (:mod:`scenarios.api`), the ones
  every ``rnhql`` subcommand makes, returning :class:`Run`, :class:`Comparison`,
  :class:`Grade`, :class:`Optimum`, :class:`Aliasing`, :class:`Crosscheck`; bad input
  raises :class:`InputError` naming the argument and the fix;
- :class:`Scenario`, :class:`Circle`, :class:`Robot`, :class:`Rewards`: a world built in
  Python; :class:`Fidelity` and :data:`RUNGS`: the physics world's ladder;
- :data:`ENV_IDS`: the Gymnasium ids, registered on import (``gymnasium.make("rnhql/...")``).

The repository's packages (``sim``, ``learning``, ``scenarios``) stay importable as before;
this face only re-exports them, so nothing here is a second implementation.
"""

from __future__ import annotations

from scenarios.api import (
    Aliasing,
    Comparison,
    Crosscheck,
    Grade,
    InputError,
    Optimum,
    Run,
    TrainPlan,
    aliasing,
    compare,
    crosscheck,
    grade,
    optimum,
    route,
    train,
)
from sim.envs import ENV_SPECS
from sim.physics.fidelity import PRESETS, Fidelity
from sim.scenario import Circle, Rewards, Robot, Scenario

ENV_IDS = tuple(ENV_SPECS)  # registered with Gymnasium by ``import sim`` (done above)
RUNGS = tuple(PRESETS)  # the fidelity ladder's rungs, by name

__all__ = ["ENV_IDS", "RUNGS", "Aliasing", "Circle", "Comparison", "Crosscheck", "Fidelity",
           "Grade", "InputError", "Optimum", "Rewards", "Robot", "Run", "Scenario", "TrainPlan",
           "aliasing", "compare", "crosscheck", "grade", "optimum", "route", "train"]
