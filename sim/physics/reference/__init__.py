"""The reference world: one robot in a ``pymunk.Space``, every step through Chipmunk,
and the primitive controller. The oracle the compiled kernel is tested against.
"""
