"""A seed's independent random streams: start cells, the learner, evaluation.

Common random numbers: every method trained with one seed must see the same
sequence of start cells, or two methods' difference mixes what they learn with
where they happened to start. One generator for both would not do that: a
method that draws more exploration numbers shifts every later start. So each
seed spawns independent child streams (``numpy.random.SeedSequence.spawn``):

- ``starts``: the start cell of each episode (the same for every method, in the
  fused kernel and in the step agent alike);
- ``learner``: initial weights, exploration, ties, planning;
- ``evaluation``: the epsilon-greedy rollouts of the paper's test protocol,
  which must never move the other two;
- ``physics``: the physics world's own noise (wheel noise at the ``noisy``
  fidelity), so a noisy world never moves the learner's draws.

Children 0-2 are what they were before ``physics`` (child 3) was added.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Streams:
    starts: np.random.Generator
    learner: np.random.Generator
    evaluation: np.random.Generator
    physics: np.random.Generator


def streams(seed: int) -> Streams:
    """The independent streams of ``seed`` (children 0..3 of its SeedSequence)."""
    starts, learner, evaluation, physics = np.random.SeedSequence(seed).spawn(4)
    return Streams(np.random.default_rng(starts), np.random.default_rng(learner),
                   np.random.default_rng(evaluation), np.random.default_rng(physics))
