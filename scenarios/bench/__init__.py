"""Benchmarks: grid build, learners, physics, sweep backends and recording overhead.

May import ``runs``, ``experiments``, ``recording`` and the lower layers; only ``cli`` imports it.
"""
