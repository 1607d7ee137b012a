"""The worlds of rnhql: scenarios, the grid model, the Pymunk physics world, gymnasium envs.

Importing the package registers the environment ids (``rnhql/GridRoute-v0``,
``rnhql/PhysicsRoute-v0``, ``rnhql/DiffDrive-v0``), as other environment packages
do; ``gymnasium.register_envs(sim)`` says so explicitly, and
``gymnasium.make("sim.envs:rnhql/GridRoute-v0")`` works from a fresh process.
Entry points are strings, so nothing heavy (pymunk) is imported until an env is made.
"""

from sim import envs as envs  # registers the environment ids
