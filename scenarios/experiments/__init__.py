"""Experiments a user runs: ``compare``, ``reproduce_paper``, ``continuous_vs_grid``.

Each turns a list of runs (:mod:`scenarios.runs`) into results, a report and figures.
May import ``runs``, ``recording``, ``figures``, ``sim`` and ``learning``;
never ``cli`` or ``bench``.
"""
