"""Gymnasium registration of the rnhql environments.

``import sim.envs`` registers the ids; ``gymnasium.make("sim.envs:rnhql/GridRoute-v0")``
does the import for you. Entry points are strings so nothing heavy (pymunk) is
imported until an env is made.
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry

ENV_SPECS = {
    "rnhql/GridRoute-v0": ("sim.grid.env:GridRouteEnv", 600),
    "rnhql/PhysicsRoute-v0": ("sim.physics.envs:PhysicsRouteEnv", 600),
    "rnhql/DiffDrive-v0": ("sim.physics.envs:DiffDriveEnv", 2000),
}
# make_vec(id, num_envs=N, vectorization_mode="vector_entry_point"): N robots in one Space
VECTOR_ENTRY_POINTS = {
    "rnhql/PhysicsRoute-v0": "sim.physics.vector:PhysicsRouteVectorEnv",
    "rnhql/DiffDrive-v0": "sim.physics.vector:DiffDriveVectorEnv",
}


def register_envs() -> None:
    for env_id, (entry_point, max_steps) in ENV_SPECS.items():
        if env_id not in registry:
            register(id=env_id, entry_point=entry_point, max_episode_steps=max_steps,
                     vector_entry_point=VECTOR_ENTRY_POINTS.get(env_id))


register_envs()
