"""The built-in scenarios (``*.toml``) and the Moving AI maps they use (``maps/``): data only.

Package data of ``sim`` (see ``[tool.setuptools.package-data]``), so an installed
``sim`` finds them with :func:`sim.scenario_io.builtin_dir`; no code here is imported.
"""
