"""The composition layer of rnhql: the only package that imports both ``sim`` and ``learning``.

Beside them: ``api`` and ``values`` (the library face: train, compare, grade, optimum and
the typed values they return), ``artifacts`` (results as code) and ``signals``.

Subpackages, top to bottom (a package imports only those below it):

- ``cli``: the ``rnhql`` command, one module per subcommand;
- ``bench``: the benchmarks behind ``rnhql bench`` and ``python -m scenarios.bench.*``;
- ``studies``: the scripts behind the docs' tables (the paper, the ladder, maps);
- ``sweep``: many runs and their owner ``run_sweep`` (backends, output folder, resume,
  Ctrl-C, the comparison recording);
- ``runs``: run specs, one run end to end, the ``results.json`` contract;
- ``recording``: Rerun recordings of runs and comparisons;
- ``figures``: matplotlib figures and route drawings;
"""

import importlib.util
from pathlib import Path as _Path


def _check_siblings() -> None:
    """Refuse, in one line, a ``sim.py`` or ``learning.py`` of the user's that hides rnhql's
    package of that name (the script's folder comes first on ``sys.path``): without this the
    first sign is an obscure error deep inside an import, or Gymnasium's "Namespace rnhql
    not found"."""
    home = _Path(__file__).resolve().parent.parent
    for name in ("sim", "learning"):
        spec = importlib.util.find_spec(name)
        origin = None if spec is None else spec.origin
        if origin is not None and _Path(origin).resolve() != home / name / "__init__.py":
            raise ImportError(f"{origin} hides rnhql's '{name}' package (a module named "
                              f"{name} beside your script comes first on sys.path): rename "
                              "that file")


_check_siblings()
