"""Rerun recordings: the file, the scene and blueprints, batched episode logging, the
training-loop hooks and comparison recordings.

May import ``sim`` and ``learning`` (read-outs only); never ``runs``, ``sweep``,
``studies`` or ``cli``.
"""
