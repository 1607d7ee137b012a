"""Studies: the scripts behind the docs' tables, each ``python -m scenarios.studies.ROOM.NAME``.

- :mod:`scenarios.studies.paper`: the paper's claims (reproduce_paper, reward design, the
  oracle bound, scaling over the paper's arenas);
- :mod:`scenarios.studies.ladder`: the fidelity ladder (continuous vs gridded,
  predictivity, the grading check, aliasing);
- :mod:`scenarios.studies.maps`: maps of many kinds (the suite, the RNH-QL+ ablation,
  held-out maps, large maps, the greedy test from S);
- :mod:`scenarios.studies.args`: one way to declare a script's arguments.

Each turns sweeps (:mod:`scenarios.sweep`) into a report, figures and an artifact
(:mod:`scenarios.artifacts`). May import ``sweep``, ``runs``, ``recording``, ``figures``,
``sim`` and ``learning``; never ``cli`` or ``bench``.
"""
