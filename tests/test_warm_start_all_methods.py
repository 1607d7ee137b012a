"""Every registered method can start a physics run from the grid (issue 62's first target):
its own file, so that its compile of every method's physics kernels (minutes on a cold
cache) runs beside the other warm-start tests, not after them."""

from __future__ import annotations

from learning.methods.registry import METHODS, comparison_methods
from scenarios import api


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
