"""The Pymunk side of a scenario, in four rooms around the fidelity ladder.

The package's best idea is the split between an **oracle** and a **fast path**: every
fidelity knob is first written in the reference world, every step through Chipmunk, and
the compiled kernel is tested against it
(``tests/test_physics_batch.py::test_batch_robot_equals_the_reference_world``) before
anything learns on it.

- here: :mod:`~sim.physics.fidelity` (the ladder of named presets, each knob in SI),
  :mod:`~sim.physics.static` (collision types, :class:`~sim.physics.static.PhysicsConfig`,
  contacts, static shapes, a Space), :mod:`~sim.physics.drive_profiles` (the drive's limits
  and its discrete velocity profiles), :mod:`~sim.physics.sigint` (Ctrl-C inside Chipmunk
  callbacks) and :mod:`~sim.physics.jitcache` (numba's disk cache, dropped when a source
  changes);
- :mod:`sim.physics.reference`: the oracle. One robot in a ``pymunk.Space``, every step
  through Chipmunk, and the primitive controller at every fidelity;
- :mod:`sim.physics.kernel`: the fast path. The primitive for many robots in compiled code
  (free motion integrated as Chipmunk integrates it, contact steps handed back to
  Chipmunk), its geometry queries and named state, and the batch of N robots in one Space;
- :mod:`sim.physics.envs`: the gymnasium envs and their vector forms, on the fast path;
- :mod:`sim.physics.models`: what is built by driving: the tabular transition model, the
  stochastic model at a fidelity (V*), policy rollouts, the continuous optimum.

Each room imports only the rooms above it in this list (``tests/test_architecture.py``).
"""

from sim.physics.jitcache import drop_stale_cache as _drop_stale_cache

_drop_stale_cache()
