"""The Pymunk side of a scenario: config, static shapes, the world, the primitive controller,
the fast primitive kernel, the batched world, the transition model and the envs.

Modules, in import order (each imports only those above it):

- :mod:`sim.physics.sigint`: Ctrl-C while Chipmunk calls back into Python;
- :mod:`sim.physics.static`: collision types, :class:`PhysicsConfig`, contacts, static shapes,
  a Space, a robot's bodies;
- :mod:`sim.physics.world`: one robot in a ``pymunk.Space``, every step through Chipmunk
  (the reference world, and ``DiffDrive``'s);
- :mod:`sim.physics.controller`: diff-drive kinematics, discrete profiles and the leg plan
  (compiled, shared with the kernel), the reference primitive controller at every fidelity;
- :mod:`sim.physics.kernel_state`: the kernel's state by name (robot records, constants);
- :mod:`sim.physics.kernel`: the primitive for many robots in compiled code, free motion
  integrated as Chipmunk integrates it, contact steps handed back to Chipmunk;
- :mod:`sim.physics.batch`: N robots in one ``pymunk.Space`` driven by that kernel;
- :mod:`sim.physics.model`: the physics world's own tabular model (graded tests);
- :mod:`sim.physics.envs`, :mod:`sim.physics.diffdrive_env`, :mod:`sim.physics.vector`:
  the gymnasium envs (:mod:`sim.physics.env_parts`: what they share).
"""

from sim.physics.jitcache import drop_stale_cache as _drop_stale_cache

_drop_stale_cache()
