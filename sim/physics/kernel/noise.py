"""A robot's normals (wheel noise, odometry, fixes, slips), drawn in compiled code.

Each robot reads its own generator's stream in blocks of ``noise.shape[1]`` normals; a
primitive that needs more than its block has left starts the next block (the rest is never
used): which normals a run uses depends on that layout, so it stays as it always was.
Within a block, normals are drawn as they are needed, ``FIRST_NOISE_BLOCK`` first, then
doubling (a graded drive often ends within a few hundred, and a Generator's normals are
the same drawn in any chunks): the block's next chunk joins its drawn part.

Numba's ``standard_normal`` is numpy's algorithm on the same bit generator (the same
normals, bit for bit) at about a quarter of the cost of numpy's own fill here (3 ns a
normal against 11), and a robot above ``exact`` reads two normals a control period, so
the refill is compiled and called from inside the kernel's loops (the graded drives, the
fused training step); :func:`refill_one` is the same for Python callers.
"""

from __future__ import annotations

from numba import njit

from sim.physics.generator_handle import generator_from
from sim.physics.kernel.state import BORROWS


@njit(**BORROWS)
def refill(i, noise, npos, nend, nblock, rng):
    """Robot ``i``'s next normals from ``rng``: the block goes on (doubling chunks) or a new
    block starts. ``npos[i]``: the next unread normal; ``nend[i]``: the end of those drawn."""
    width, end = noise.shape[1], nend[i]
    if end < width:  # the block goes on
        k = min(nblock[i], width - end)
        for j in range(end, end + k):
            noise[i, j] = rng.standard_normal()
        nend[i] = end + k
    else:  # a new block
        k = min(nblock[i], width)
        for j in range(k):
            noise[i, j] = rng.standard_normal()
        npos[i], nend[i] = 0, k
    nblock[i] = 2 * k


@njit(cache=True)
def refill_one(i, noise, npos, nend, nblock, noise_h):
    """:func:`refill` of robot ``i`` from its generator handle ``noise_h[i]``."""
    refill(i, noise, npos, nend, nblock, generator_from(noise_h[i]))
