"""Gymnasium registration of the rnhql environments.

``import sim`` (or ``import sim.envs``) registers the ids; ``gymnasium.make(
"sim:rnhql/GridRoute-v0")`` does the import for you. Gymnasium 1.x has no plugin
mechanism that registers an installed package's ids without importing it (its 0.x
``gymnasium.envs`` entry points are gone), so a script imports ``sim`` first. Entry points
are strings so nothing heavy (pymunk) is imported until an env is made.

Every id is registered with ``rewards="goal-only"`` (see :data:`sim.env_args.DEFAULT_REWARDS`
for why) and no ``max_episode_steps``: each env truncates itself after its scenario's
``steps_per_episode`` (``steps_per_episode=`` overrides it), so ``ost003d``'s 1704 moves
are honoured; ``gymnasium.make(..., max_episode_steps=n)`` still adds a ``TimeLimit``.
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry

from sim.env_args import DEFAULT_REWARDS

ENV_SPECS = {
    "rnhql/GridRoute-v0": "sim.grid.env:GridRouteEnv",
    "rnhql/PhysicsRoute-v0": "sim.physics.envs.route:PhysicsRouteEnv",
    "rnhql/DiffDrive-v0": "sim.physics.envs.diffdrive:DiffDriveEnv",
}
# make_vec(id, num_envs=N, vectorization_mode="vector_entry_point"): N robots in one Space
VECTOR_ENTRY_POINTS = {
    "rnhql/GridRoute-v0": "sim.grid.env:grid_vector_env",
    "rnhql/PhysicsRoute-v0": "sim.physics.envs.vector:PhysicsRouteVectorEnv",
    "rnhql/DiffDrive-v0": "sim.physics.envs.vector:DiffDriveVectorEnv",
}
DEFAULT_KWARGS = {"rewards": DEFAULT_REWARDS}


def register_envs() -> None:
    for env_id, entry_point in ENV_SPECS.items():
        if env_id not in registry:
            register(id=env_id, entry_point=entry_point, max_episode_steps=None,
                     vector_entry_point=VECTOR_ENTRY_POINTS.get(env_id),
                     kwargs=dict(DEFAULT_KWARGS))


register_envs()
