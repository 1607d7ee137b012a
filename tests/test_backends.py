"""The Ray backend gives the same results.json as the local pool (timings aside)."""

from __future__ import annotations

import json
import os

import pytest

from scenarios.experiments.compare import make_specs, run_sweep
from scenarios.runs.backends import BackendError, run_local, run_ray

TIMING = ("wall_time_s", "wall_time_per_episode_s")


def strip_timings(results: dict) -> dict:
    for run in results["runs"]:
        for key in TIMING:
            run.pop(key)
    for per_world in results["summary"].values():
        for entry in per_world.values():
            entry.pop("wall_time_s")
    return results


@pytest.mark.ray
def test_ray_and_local_backends_agree(tmp_path):
    pytest.importorskip("ray")
    os.environ.setdefault("RAY_AUTH_MODE", "disabled")
    specs = make_specs("paper-40", ["rnh-ql", "dyna-q"], [0, 1], 30, ["grid"])
    local = run_sweep(specs, tmp_path / "local", run_local, jobs=2, figures=False)
    ray = run_sweep(specs, tmp_path / "ray", run_ray, num_cpus=2, figures=False)
    assert strip_timings(local) == strip_timings(ray)
    on_disk = json.loads((tmp_path / "ray" / "results.json").read_text())
    assert len(on_disk["runs"]) == 4


def test_missing_ray_says_how_to_install(monkeypatch):
    import builtins

    real_import = builtins.__import__

    def no_ray(name, *args, **kwargs):
        if name == "ray":
            raise ImportError("no ray")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_ray)
    with pytest.raises(BackendError, match=r"pip install 'rnhql\[ray\]'"):
        run_ray(make_specs("paper-40", ["st-ql"], [0], 5, ["grid"]))
