"""Every registered method can start a physics run from the grid (issue 62's first target).
It compiles every method's physics kernels (minutes on a cold cache), so it is a slow test:
``pytest -m slow tests/test_warm_start_all_methods.py``."""

from __future__ import annotations

import pytest

from learning.methods.registry import METHODS, comparison_methods
from scenarios import api


@pytest.mark.slow  # minutes on a cold cache (CI): `pytest -m slow`; the default run warm-starts
#                   haql, rnh-ql+, mf-r-max and plain learners (tests/test_warm_start.py)
def test_every_registered_method_warm_starts_in_physics():
    """Every registered method (the compared ones, the named variants and the references run
    on request, mf-r-max among them) runs a pretrained physics run."""
    methods = list(METHODS)
    assert set(comparison_methods()) < set(methods) and "mf-r-max" in methods
    cmp = api.compare("paper-40", methods, worlds="physics", seeds=1, episodes=2,
                      pretrain=("grid", 5), jobs=1)
    assert len(cmp.runs) == len(methods)
    for run in cmp.runs:
        assert run.pretrain["episodes"] == 5 and run.episodes == 2, run.method
