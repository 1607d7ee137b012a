"""The learners: RNH-QL and its baselines over grid states. numpy + numba only.

Rooms, each importing only those above it in this list:

- here: the config base and its limits, what a learner may know of the world (geometry),
  random streams, the metrics that rank learners, numba's disk cache;
- :mod:`learning.parts`: what methods are built of (tabular rules, traces, RBF and MLP,
  the move model, the free-space model and its walks, the tally);
- :mod:`learning.plain`: your own learner in plain Python, and any policy as a state;
- :mod:`learning.methods`: one module per method (``q_learning``, ``q_lambda``,
  ``dyna_q``, ``pfh_rl``, ``sarsa_rs``, ``haql``, ``rn_ql``, ``rnh_ql``, ``rnh_ql_plus``,
  and the RNH-QL+ ablation's ``rnh_ql_plus_ablation``), each with its config, named state
  and hooks, and :mod:`learning.methods.registry`, the one method list;
- :mod:`learning.compiled`: the compiled plumbing (one door onto every method's hooks,
  the fused kernels, named states, the generator handle, read-outs);
- :mod:`learning.drivers`: what runs a learner (fused training, its plain-Python mirror,
  the step and batch agents, checkpoints).

Never imports sim, scenarios, pymunk or rerun:
worlds reach the learners as a duck-typed :class:`TabularMDP` (fused kernels) or a
gymnasium env plus a :class:`Geometry` (step-by-step agent).
"""

from learning.jitcache import drop_stale_cache, prefer_quick_compile

prefer_quick_compile()  # before anything compiles

from learning.config import MethodConfig
from learning.drivers.agent import EpisodeLog, StepAgent, make_agent, run_env_episodes
from learning.drivers.checkpoint import (
    Checkpoint,
    CheckpointError,
    load_checkpoint,
    save_checkpoint,
)
from learning.drivers.state import copy_state, init_state
from learning.drivers.train import TrainResult, greedy_test, train_tabular
from learning.geometry import Geometry, TabularMDP, geometry_of
from learning.methods.dyna_q import DynaQ
from learning.methods.haql import HAQL
from learning.methods.pfh_rl import PFHRL
from learning.methods.q_lambda import QLambda
from learning.methods.q_learning import STQL, QOpt
from learning.methods.registry import METHODS, config_from_fields
from learning.methods.rn_ql import RNQL
from learning.methods.rnh_ql import RNHQL
from learning.methods.rnh_ql_plus import RNHQLPlus, RNHQLPlusExplore
from learning.methods.rnh_ql_plus_ablation import RNHQLPlusAblation
from learning.methods.sarsa_rs import SarsaRS

drop_stale_cache()  # numba reads its cache at a function's first call, which is later

__all__ = [
    "HAQL", "METHODS", "PFHRL", "RNHQL", "RNQL", "STQL", "Checkpoint", "CheckpointError",
    "DynaQ", "EpisodeLog", "Geometry", "MethodConfig", "QLambda", "QOpt", "RNHQLPlus",
    "RNHQLPlusAblation", "RNHQLPlusExplore", "SarsaRS", "StepAgent", "TabularMDP", "TrainResult",
    "config_from_fields", "copy_state", "geometry_of", "greedy_test", "init_state",
    "load_checkpoint", "make_agent", "run_env_episodes", "save_checkpoint", "train_tabular",
]
