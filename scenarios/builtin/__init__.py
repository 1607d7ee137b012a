"""The built-in scenarios (``*.toml``) and the Moving AI maps they use (``maps/``): data only.

:func:`sim.scenario_io.builtin_dir` finds this folder by path; no code here is imported.
"""
