"""The composition layer of rnhql: the only package that imports both ``sim`` and ``learning``.

Subpackages, top to bottom (a package imports only those below it):

- ``cli``: the ``rnhql`` command, one module per subcommand;
- ``bench``: the benchmarks behind ``rnhql bench`` and ``python -m scenarios.bench.*``;
- ``experiments``: comparisons, the paper's experiments, continuous vs grid;
- ``runs``: run specs, one run end to end, sweep backends, the ``results.json`` contract;
- ``recording``: Rerun recordings of runs and comparisons;
- ``figures``: matplotlib figures and route drawings;
- ``builtin``: the built-in scenario TOMLs and Moving AI maps (data only).
"""
