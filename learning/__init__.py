"""The learners: RNH-QL and its baselines over grid states. numpy + numba only.

Never imports sim, scenarios, pymunk or rerun: worlds reach the learners as a
duck-typed :class:`TabularMDP` (fused kernels) or a gymnasium env plus a
:class:`Geometry` (step-by-step agent).
"""

from learning.agent import EpisodeLog, StepAgent, make_agent, run_env_episodes
from learning.checkpoint import Checkpoint, CheckpointError, load_checkpoint, save_checkpoint
from learning.geometry import Geometry, TabularMDP, geometry_of
from learning.jitcache import drop_stale_cache
from learning.methods import (
    HAQL,
    METHODS,
    PFHRL,
    RNHQL,
    RNQL,
    STQL,
    DynaQ,
    MethodConfig,
    QLambda,
    QOpt,
    SarsaRS,
    config_from_fields,
)
from learning.state import AgentState, init_state
from learning.train import TrainResult, greedy_test, train_tabular

drop_stale_cache()  # numba reads its cache at a function's first call, which is later

__all__ = [
    "HAQL", "METHODS", "PFHRL", "RNHQL", "RNQL", "STQL", "AgentState", "Checkpoint",
    "CheckpointError", "DynaQ", "EpisodeLog", "Geometry", "MethodConfig", "QLambda", "QOpt",
    "SarsaRS", "StepAgent", "TabularMDP", "TrainResult", "config_from_fields", "geometry_of",
    "greedy_test", "init_state", "load_checkpoint", "make_agent", "run_env_episodes",
    "save_checkpoint", "train_tabular",
]
