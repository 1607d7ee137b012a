"""The Ray backend gives the same results.json as the local pool (timings aside)."""

from __future__ import annotations

import json
import os

import pytest

from scenarios.sweep.backends import BackendError, run_local, run_ray
from scenarios.sweep.run import make_specs, run_sweep

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


def test_progress_off_a_terminal_prints_a_line_every_interval_and_at_the_end():
    import io
    import time

    from scenarios.sweep.backends import Progress

    out = io.StringIO()  # not a TTY
    p = Progress(3, interval_s=0.05, stream=out)
    time.sleep(0.2)  # no run has finished: the heartbeat still speaks
    beats = out.getvalue().count("progress: 0/3 runs done")
    assert beats >= 2
    for _ in range(3):
        p.update("x")
    lines = out.getvalue().splitlines()
    assert lines[-1].startswith("progress: 3/3 runs done")
    n = len(lines)
    time.sleep(0.15)
    assert len(out.getvalue().splitlines()) == n  # stopped after the last run
    quiet = io.StringIO()
    q = Progress(2, enabled=False, interval_s=0.01, stream=quiet)
    time.sleep(0.05)
    q.close()
    assert quiet.getvalue() == ""


def test_progress_counts_episodes_across_workers_and_estimates_from_the_rate(tmp_path):
    """Progress is measured in episodes finished in every worker process; the first time
    left it gives, plus the time already elapsed, is within 2x of the sweep's wall time
    (it waits out the compilation instead of extrapolating from it)."""
    import io
    import re
    import time

    from scenarios.sweep.backends import Progress, run_local
    from scenarios.sweep.run import make_specs, run_sweep

    specs = make_specs("paper-40", ["st-ql", "q-lambda", "rnh-ql"], [0, 1, 2, 3], 4000,
                       ["grid"])
    out = io.StringIO()
    progress = Progress(len(specs), interval_s=0.5, stream=out, window_s=5.0)
    t0 = time.perf_counter()
    run_sweep(specs, tmp_path / "s", run_local, figures=False, jobs=2, progress=progress)
    wall = time.perf_counter() - t0
    lines = out.getvalue().splitlines()
    assert lines[-1] == "writing results.json, summary.md and the figures…"  # the tail, named
    lines = [ln for ln in lines if ln.startswith("progress: ")]
    assert lines[-1].startswith(f"progress: {12 * 4000:,}/{12 * 4000:,} episodes (100 %)")
    first = next((ln for ln in lines if "s left" in ln), None)
    compiling = [i for i, ln in enumerate(lines) if "compiling kernels" in ln]
    if compiling:  # a cold cache: no estimate until no worker compiles
        assert not any("s left" in ln for ln in lines[:compiling[-1]]), lines
        compiled_at = float(re.search(r"(\d+) s elapsed", lines[compiling[-1]]).group(1))
    else:
        compiled_at = 0.0
    if wall - compiled_at < 8:  # too little work after the compile for an estimate to be due
        return
    assert first is not None, lines
    elapsed, left = (float(x) for x in re.search(r"(\d+) s elapsed, ~(\d+) s left",
                                                 first).groups())
    assert 0.5 * wall <= elapsed + left <= 2.0 * wall, (first, wall)


def test_no_estimate_while_a_worker_compiles_and_the_rate_restarts_after():
    """A worker in the first task of a method (on a cold cache: compiling) withholds the
    first estimate and is never measured as a rate (a rate measured across a compile once
    gave an estimate 8x too long); once an estimate exists, a later compile keeps it (the
    last rate carries it), and the rate window restarts after the compile."""
    from scenarios.runs import work
    from scenarios.sweep.backends import Progress

    p = Progress(4, enabled=False)
    p.expect(4, 10_000)
    with work.warm_up(["st-ql", "haql"]):
        assert work.warming(p.counter) == 1
        assert p.eta_s(now=0.0) is None
        assert "compiling kernels (no estimate yet)" in p._line()
        work.add_episodes(1000)  # the first episodes end this process's warm-up
        assert work.warming(p.counter) == 0
    with work.warm_up(["haql"]):  # warm in this process already
        assert work.warming(p.counter) == 0
    assert p.eta_s(now=10.0) is None  # one sample is no rate
    work.add_episodes(1000)
    assert p.eta_s(now=15.0) == pytest.approx(8000 / 200)
    p.counter[work.WARMING] = 1  # another worker starts compiling: the last rate carries on
    work.add_episodes(0)
    assert p.eta_s(now=16.0) == pytest.approx(8000 / 200)
    assert "compiling" not in p._line()
    p.counter[work.WARMING] = 0
    work.add_episodes(4000)
    assert p.eta_s(now=20.0) == pytest.approx(4000 / 200)  # one sample: the last rate still
    work.add_episodes(1000)
    assert p.eta_s(now=25.0) == pytest.approx(3000 / 200)  # the new window's rate


def test_each_world_is_estimated_from_its_own_rate():
    """A mixed sweep: grid episodes flow first and fast, physics episodes slowly; the time
    left is each world's episodes left over its own rate, and none until physics has one."""
    from scenarios.runs import work
    from scenarios.sweep.backends import Progress

    p = Progress(4, enabled=False)
    p.expect(4, 2000, physics_episodes=1000)
    assert p.eta_s(now=0.0) is None
    work.add_episodes(500)
    assert p.eta_s(now=1.0) is None
    work.add_episodes(500)  # every grid episode done in 4 s
    assert p.eta_s(now=5.0) is None  # physics has work left and no rate yet
    work.add_episodes(10, physics=True)
    assert p.eta_s(now=6.0) is None
    work.add_episodes(40, physics=True)
    assert p.eta_s(now=11.0) == pytest.approx(950 / 8)  # 40 physics episodes in 5 s
    p.close()
    work.share(None)
    p.close()
    work.share(None)
