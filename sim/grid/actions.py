"""The grid's four actions: the one place the sim side writes out their order.

Action indices are all the learners see (``learning`` never imports ``sim``), so
everything that turns an index into a move, a heading, a name or its reverse
reads it here; a second copy could silently disagree.
"""

from __future__ import annotations

import math

ACTION_NAMES = ("up", "down", "left", "right")
ACTION_DELTAS = ((0, 1), (0, -1), (-1, 0), (1, 0))  # (dx, dy) in cells; y grows upwards
ACTION_HEADINGS = (math.pi / 2, -math.pi / 2, math.pi, 0.0)  # [rad] the robot faces to move
OPPOSITE = (1, 0, 3, 2)  # the action that undoes each one
N_ACTIONS = len(ACTION_DELTAS)
