"""Learn on the grid, finish on the robot: a plain-Python learner pretrained in the grid, then
trained at the ``slip`` rung (wheels that slip now and then), against the same learner
trained at the rung from scratch; how much robot time the grid saved (docs/ladder.md,
"How much robot time does the grid save?").

The learner is the count-bonus Q-learner of ``examples/script_own_learner.py``. The grid
phase costs no robot time; its policy is graded at the rung before the robot drives a
single primitive (the run's ``pretrain`` entry). From the command line the same two phases
are ``rnhql train maze-1 --method haql --save grid.npz`` then ``rnhql train maze-1 --method
haql --world physics --fidelity slip --init grid.npz`` (compiled methods), or
``rnhql compare ... --world physics --pretrain grid:300`` for a sweep.

Run as pasted: ``python examples/script_grid_then_robot.py`` (about a minute);
``RNHQL_EXAMPLE_SCALE=0.01`` shrinks the budget (CI does).
"""

import os
import sys
from pathlib import Path

import rnhql

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the learner's own example file
from script_own_learner import CountBonusQ

SCALE = float(os.environ.get("RNHQL_EXAMPLE_SCALE", "1"))
GRID_EPISODES = max(20, round(300 * SCALE))
ROBOT_EPISODES = max(5, round(100 * SCALE))

if __name__ == "__main__":
    grid = rnhql.train("paper-40", CountBonusQ, episodes=GRID_EPISODES, seed=0)
    print(f"grid: {grid}")
    warm = rnhql.train("paper-40", CountBonusQ, world="physics", fidelity="slip",
                       episodes=ROBOT_EPISODES, seed=0, init=grid)
    cold = rnhql.train("paper-40", CountBonusQ, world="physics", fidelity="slip",
                       episodes=ROBOT_EPISODES, seed=0)
    before = warm.pretrain["policy"]["p_goal"]
    print(f"the grid's policy at slip, before any robot time: P(G) {before:.2f}")
    for label, run in (("grid, then robot", warm), ("robot only", cold)):
        print(f"{label}: P(G) {run.p_goal:.2f} after {run.robot_primitives:,} primitives "
              f"({run.robot_seconds / 3600:.2f} robot-hours)")
    if before >= cold.p_goal:  # the grid's policy, no robot time, matched the rung alone
        print(f"robot time saved by the grid: {cold.robot_seconds / 3600:.2f} robot-hours "
              f"(the grid's policy at P(G) {before:.2f} without driving, the robot alone "
              f"{cold.p_goal:.2f} after {cold.robot_primitives:,} primitives)")
    else:
        print(f"robot time saved by the grid: none here (the robot alone reached P(G) "
              f"{cold.p_goal:.2f}, the grid's policy {before:.2f}; after the grid, the robot "
              f"reached {warm.p_goal:.2f})")
