"""Runs and sweeps: :class:`~scenarios.runs.spec.RunSpec`, one run end to end (grid or
physics), the local and Ray backends, and the ``results.json`` contract.

May import ``recording``, ``sim`` and ``learning``; never ``experiments``, ``bench`` or ``cli``.
"""
