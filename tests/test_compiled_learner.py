"""A plain learner written as a numba ``@jitclass`` runs in a compiled loop: the same runs as
the compiled method it ports, its failures said as any learner's, nothing left in numba's
on-disk cache; recorded, resumed and graded in physics as a Python learner is."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from learning.plain.learner import LearnerError
from scenarios import api
from tests.plain_learners import differing
from tests.plain_learners.features import check_recorded, check_resumes_and_graded

JIT = "tests.plain_learners.st_ql_jit:STQLJit"


def test_a_jitclass_port_of_st_ql_equals_compiled_st_ql_in_grid_and_physics():
    cmp = api.compare("paper-40", ["st-ql", JIT], worlds=("grid", "physics"), seeds=2,
                      episodes=20, jobs=1)
    for world in ("grid", "physics"):
        for ours, theirs in zip(cmp.of("st-ql", world), cmp.of(JIT, world), strict=True):
            assert differing(dict(ours.record), dict(theirs.record)) == []
            assert np.array_equal(ours.policy, theirs.policy)


def _numba_cache_files() -> set[Path]:
    here = Path(__file__).resolve().parent.parent
    places = [here]
    if os.environ.get("NUMBA_CACHE_DIR"):
        places.append(Path(os.environ["NUMBA_CACHE_DIR"]))
    import numba
    places.append(Path(numba.__file__).parent)
    return {p for d in places if d.is_dir() for p in d.rglob("*.nb[ic]")}


def test_a_jitclass_run_leaves_nothing_in_numbas_cache():
    """Grid and physics (the compiled physics loop too): after the compiled methods' kernels
    are cached, a jitclass learner's runs add no file to any numba cache."""
    api.train("paper-40", method="st-ql", episodes=5, world="physics", fidelity="noisy")
    api.train("paper-40", method="st-ql", episodes=5)
    before = _numba_cache_files()
    api.train("paper-40", method=JIT, episodes=5)
    api.train("paper-40", method=JIT, episodes=5, world="physics", fidelity="noisy")
    assert _numba_cache_files() - before == set()


def test_a_jitclass_answering_no_action_fails_the_run_naming_it():
    import numba
    from numba import types
    from numba.experimental import jitclass

    @jitclass([("n", types.int64)])
    class Four:
        def __init__(self, n_states, n_actions, rng):
            self.n = n_actions

        def act(self, s):
            return 4

        def update(self, s, a, r, s2, terminal):
            pass

        def greedy(self, s):
            return 0

    assert numba is not None
    with pytest.raises(LearnerError, match=r"Four\.act\(\d+\) returned 4, not an action"):
        api.train("paper-40", method=Four, episodes=3)
    with pytest.raises(LearnerError, match=r"Four\.act\(\d+\) returned 4, not an action"):
        api.train("paper-40", method=Four, episodes=3, world="physics")  # the compiled loop


_BROKEN = '''
import numpy as np
from numba import types
from numba.experimental import jitclass


@jitclass([("q", types.float64[:, :])])
class Broken:
    def __init__(self, n_states, n_actions, rng):
        self.q = np.zeros((n_states, n_actions))

    def act(self, s):
        return self.q[s].no_such_thing()

    def update(self, s, a, r, s2, terminal):
        pass

    def greedy(self, s):
        return 0
'''


def test_a_jitclass_that_does_not_compile_is_refused_up_front_in_one_line(tmp_path):
    """Before any run: one line with numba's reason and the learner's own file and line,
    exit 2 from the command (not numba's page of typing traces, not a failed run)."""
    import subprocess
    import sys

    (tmp_path / "brokenjit.py").write_text(_BROKEN)
    env = dict(os.environ, PYTHONPATH=f"{tmp_path}{os.pathsep}"
               f"{os.environ.get('PYTHONPATH', '')}")
    out = subprocess.run([sys.executable, "-m", "scenarios.cli", "train", "paper-40",
                          "--method", "brokenjit:Broken", "--episodes", "3"],
                         capture_output=True, text=True, env=env, timeout=300,
                         cwd=Path(__file__).resolve().parent.parent)
    assert out.returncode == 2, out.stderr
    lines = [line for line in out.stderr.strip().splitlines()  # but the CLI's heartbeat,
             if not line.startswith("… still working")]  # printed when compiling is slow
    assert len(lines) == 1, out.stderr
    assert "brokenjit:Broken does not compile" in lines[0]
    assert "no_such_thing" in lines[0] and f"{tmp_path / 'brokenjit.py'}:13" in lines[0]
    assert "Fix: fix the class" in lines[0]
    assert "Broken on paper-40" not in out.stdout  # refused before the run was announced


def test_a_jitclass_warm_start_equals_the_python_ports():
    """--pretrain grid:N then the noisy rung: the jitclass learner is carried field by field
    (numba's instances do not pickle) and runs the Python port's run, figure for figure."""
    runs = [api.train("paper-40", method=m, world="physics", fidelity="noisy",
                      pretrain=("grid", 20), episodes=3, seed=1)
            for m in (JIT, "tests.plain_learners.st_ql:STQLPort")]
    recs = [dict(r.record) for r in runs]
    for rec in recs:  # the first phase's clock aside
        rec["pretrain"] = {k: v for k, v in rec["pretrain"].items() if k != "wall_time_s"}
    assert recs[0]["pretrain"]["episodes"] == 20
    assert differing(*recs) == []
    assert np.array_equal(runs[0].policy, runs[1].policy)



@pytest.mark.parametrize("world", ["grid", "physics"])
def test_its_run_is_recorded_like_a_python_learners(tmp_path, world):
    check_recorded(JIT, world, tmp_path)


def test_its_sweep_resumes_and_its_physics_runs_are_graded_by_their_drives(tmp_path, capsys):
    check_resumes_and_graded(JIT, tmp_path, capsys)
