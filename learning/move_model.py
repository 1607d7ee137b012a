"""A learned model of moves that may fail: what Dyna-Q and RNH-QL+ plan with.

On the grid, and in the physics world at the ``exact`` fidelity, a move from a
cell either always works or always fails, and a model that stores the last
outcome of each (s, a) is the world. With wheel noise and carried pose a move
beside an obstacle can fail once and work most of the time. A last-outcome
model then flips between "wall" and "free" with every failure: Dyna-Q replays
the failure until the move works again, and RNH-QL+'s optimistic model re-runs
its BFS, its potential moving under the Q-table each time (measured on
``paper-50`` at ``noisy``: greedy tests that flip between the optimal route and
"no G" to the last episode, 2 of 10 seeds ending with no route).

This model keeps, per (s, a), two outcomes and how often each was seen:

* the move working (the caller says what that is: RNH-QL+ asks that it reach
  the neighbour it heads for, Dyna-Q that it move at all), to the successor
  it was last seen to work to (or G), with its reward; a move that has worked
  once keeps that successor through later failures, so "known to fail" means
  "never seen to work" (a wall stays a wall, and a free move that fails now
  and then stays free);
* failing, replayed as staying put with the reward of the last failure (a
  failure that drifted into another cell is replayed as staying: an
  approximation, rare at the ``noisy`` preset). Until the move first works,
  the stored outcome is its last failure itself.

Planning draws an outcome with the frequencies seen (a sample model: the
replayed updates average to the expected backup, as Dyna's do in a stochastic
world). When only one outcome was ever seen, which is every pair of a
deterministic world, no number is drawn and the model is exactly the
last-outcome model: runs at ``exact`` are bit-for-bit those of before.

Storage (offsets per method; ``n_a`` actions): ``imap[s, a]`` the successor (-1
unseen), ``imap[s, n_a + a]`` 1 if it is G's entry, ``fmap[s, a]``
its reward; ``counts[c0 + 2 (s n_a + a)]`` works seen, ``+ 1`` failures seen;
``fvar[F_RFAIL]`` the reward of the last failure.
"""

from __future__ import annotations

from numba import njit

from learning import kinds as K

INLINE = dict(cache=True, inline="always")
COUNT_CAP = 1 << 30  # a pair's two counts are halved when their sum reaches this (int32)


@njit(**INLINE)
def observe_outcome(imap, fmap, counts, c0, fvar, n_a, s, a, r, s2, terminated, worked):
    """Record the real step s -a-> s2 (reward r) in the model. ``worked``: the move did
    what it is for (RNH-QL+: reached the neighbour it heads for; Dyna-Q: moved at all)."""
    j = c0 + 2 * (s * n_a + a)
    if counts[j] + counts[j + 1] >= COUNT_CAP:  # int32: halve, keeping the rate and any 0
        counts[j] = (counts[j] + 1) // 2
        counts[j + 1] = (counts[j + 1] + 1) // 2
    if worked:
        counts[j] += 1
    else:
        counts[j + 1] += 1
        fvar[K.F_RFAIL] = r
        if counts[j] > 0:
            return  # seen to work before: the successor stays; this was a failure among works
    imap[s, a] = s2
    imap[s, n_a + a] = 1 if terminated else 0
    fmap[s, a] = r


@njit(**INLINE)
def never_worked(imap, counts, c0, n_a, s, a):
    """Tried, and never seen to work (the optimistic model's wall)."""
    return imap[s, a] >= 0 and counts[c0 + 2 * (s * n_a + a)] == 0


@njit(**INLINE)
def replay_fails(counts, c0, n_a, s, a, rng):
    """Whether a planned replay of the seen pair (s, a) draws the failure outcome (stay
    put, ``fvar[F_RFAIL]``) instead of the stored one. Only a pair seen both to work and
    to fail draws (one ``rng.random()``), with the frequency failures were seen; a pair
    that never worked replays its stored failure, one that never failed its success."""
    j = c0 + 2 * (s * n_a + a)
    n_ok, n_fail = counts[j], counts[j + 1]
    if n_ok == 0 or n_fail == 0:
        return False
    return rng.random() * (n_ok + n_fail) < n_fail
