"""Benchmarks: grid build, learners, physics, sweep backends and recording overhead.

May import ``studies``, ``sweep``, ``runs``, ``recording`` and the lower layers; only
``cli`` imports it.
"""
