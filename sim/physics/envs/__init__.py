"""The gymnasium envs of the physics world: ``rnhql/PhysicsRoute-v0``, ``rnhql/DiffDrive-v0``
and their vector forms.
"""
