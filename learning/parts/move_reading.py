"""What a move's reward says about it: a clean arrival, or an arrival with a bump.

On the grid, and in the physics world at ``exact``, a move either reaches the
neighbour it heads for without touching anything, or bumps and stays: "reached
the neighbour" and "worked" are the same thing. With wheel noise and carried pose
a robot can graze an obstacle and still end in the neighbour cell; the world then
pays the bump reward (:meth:`sim.scenario.Rewards.of_moves`). A model learner that
counted such a move as working would plan routes that bump, and its greedy test
would trust them (measured on ``paper-50`` at ``noisy``: RNH-QL+'s routes touched
obstacles 1.2 times a drive while Dyna-Q's touched none).

The learner sees only (s, a, r, s', terminated), so it reads the bump from the
reward, as an agent must: the reward of a move that stayed put (a bump on the
grid) is the bump's; an arrival paid that reward, when free arrivals are paid
another, bumped on its way. Both rewards are learned as they are seen, so no
reward scheme is assumed. When the two are equal (``step-cost``: bump = step =
-1) the reward cannot tell them apart and every arrival counts as clean, which
is the rule of before.

Nothing changes where no move arrives with a bump (the grid, ``exact``): there
every arrival is clean and runs are bit-for-bit those of before.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

UNSEEN = np.inf  # a reward not seen yet (rewards are finite; a checkpoint refuses NaN)


class MoveReading(NamedTuple):
    r_stay: np.ndarray  # float64[1]; the reward of a move that stayed put and was not paid
    #                     like a free move (the bump's); UNSEEN until seen
    r_clean: np.ndarray  # float64[1]; the reward of a clean arrival; UNSEEN until seen


def new_move_reading() -> MoveReading:
    return MoveReading(np.full(1, UNSEEN), np.full(1, UNSEEN))


@njit(cache=True, inline="always")
def read_move(r_stay, r_clean, s, r, s2, terminated):
    """Learn from the real step s -> s2 (reward r) and say whether it arrived cleanly:
    True for a move that left s without the bump's reward (or entered G, whose reward
    takes precedence), False for a stay and for an arrival paid the bump's reward."""
    if terminated:
        return True
    if s2 == s:
        if r != r_clean[0]:  # (always, while no clean arrival is seen)
            r_stay[0] = r  # a stay paid like a free move tells nothing about bumps
        return False
    if r == r_stay[0] and r_clean[0] != UNSEEN and r != r_clean[0]:
        return False
    r_clean[0] = r
    return True


COUNT_CAP = 1 << 30  # bumps minus arrivals saturate here (int32: a long run must not wrap)


@njit(cache=True, inline="always")
def count_outcome(bal, nb, s, a, s2, clean):
    """The balance of a move after one try: a bump (stayed, or arrived paid the bump's
    reward: ``clean`` False) counts up, a clean arrival in the neighbour it heads for down;
    a move that drifted into another cell without a bump tells nothing. Returns +1 when the
    move has just become blocked (balance above 0: its likelier outcome is a bump), -1 when
    it has just become free again, 0 otherwise."""
    before = bal[s, a] > 0
    if s2 == nb[s, a] and clean:
        if bal[s, a] > -COUNT_CAP:
            bal[s, a] -= 1
    elif not clean:
        if bal[s, a] < COUNT_CAP:
            bal[s, a] += 1
    now = bal[s, a] > 0
    if now == before:
        return 0
    return 1 if now else -1
