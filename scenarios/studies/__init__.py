"""Studies: the scripts behind the docs' tables, each ``python -m scenarios.studies.ROOM.NAME``.

- :mod:`scenarios.studies.paper`: the paper's claims (reproduce_paper, reward design, the
  oracle bound, scaling over the paper's arenas);
- :mod:`scenarios.studies.ladder`: the fidelity ladder (continuous vs gridded,
  predictivity, the grading check, aliasing);
- :mod:`scenarios.studies.maps`: maps of many kinds (the suite, the RNH-QL+ ablation,
  held-out maps, large maps, the greedy test from S).

Every script declares its arguments one way (:mod:`scenarios.script_args`).

Each turns sweeps (:mod:`scenarios.sweep`) into a report, figures and an artifact
(:mod:`scenarios.artifacts`). May import ``sweep``, ``runs``, ``recording``, ``figures``,
``sim`` and ``learning``; never ``cli`` or ``bench``.
"""
