"""A compiled method from outside the package, used from the command line as
``module:Config``: it runs, and it never poisons numba's on-disk kernel cache for a later
process that does not have its module."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent

MY_QL = '''
from dataclasses import dataclass
from typing import ClassVar, NamedTuple

import numpy as np

from learning.methods import q_learning
from learning.config import BaseParams, MethodConfig
from learning.parts.tally import Tally, new_tally


@dataclass(frozen=True)
class MyQL(MethodConfig):
    name: ClassVar[str] = "MY-QL"
    cli: ClassVar[str] = "my-ql"
    q0: float = 1.0


class MyQLState(NamedTuple):  # a name of its own: numba tells states apart by it
    par: BaseParams
    tally: Tally
    q: np.ndarray


State = MyQLState


def init_state(cfg, geom, rng):
    return State(cfg.params(), new_tally(), np.full((geom.n_states, geom.n_actions), cfg.q0))


act, update = q_learning.act, q_learning.update
begin, exploit = q_learning.begin, q_learning.exploit
'''


def _run(argv: list[str], env: dict[str, str], cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "scenarios.cli", *argv], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=600)


def test_a_method_from_outside_runs_and_leaves_the_cache_clean(tmp_path):
    user = tmp_path / "user"
    (user / "mymethods").mkdir(parents=True)
    (user / "mymethods" / "__init__.py").write_text("")
    (user / "mymethods" / "my_ql.py").write_text(MY_QL)
    cache = tmp_path / "numba-cache"
    base = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "RNHQL_NO_OPTIMUM": "1"}
    with_module = {**base, "PYTHONPATH": f"{REPO}{os.pathsep}{user}"}
    first = _run(["compare", "paper-40", "--methods", "mymethods.my_ql:MyQL,st-ql", "--seeds",
                  "1", "--episodes", "10", "--jobs", "1", "--out", str(tmp_path / "a")],
                 with_module, tmp_path)
    assert first.returncode == 0, first.stderr[-2000:]
    assert "MY-QL" in (tmp_path / "a" / "summary.md").read_text() or \
        "mymethods.my_ql:MyQL" in (tmp_path / "a" / "summary.md").read_text()
    cached = [*cache.rglob("*.nbi"), *cache.rglob("*.nbc")]
    assert cached, "the run cached nothing: the test would prove nothing"
    assert not [p for p in cached if b"mymethods" in p.read_bytes()]  # (without the guard:
    #                                      kernels.*.nbi/.nbc name it, and the run below fails)
    # a later process without the user's module, on the same cache
    second = _run(["train", "paper-40", "--method", "st-ql", "--episodes", "10"],
                  {**base, "PYTHONPATH": str(REPO)}, tmp_path)
    assert second.returncode == 0, second.stderr[-2000:]


def test_a_state_numba_cannot_tell_apart_is_refused():
    """A second ``State`` with st-ql's fields would run st-ql's compiled rules (numba's
    dispatcher keys on the class's bare name and the field types)."""
    import types

    from learning.methods import q_learning
    from learning.methods.registry import register
    from tests import test_new_method as good

    twin = types.ModuleType("twin")
    for name in ("act", "update", "begin", "exploit"):
        setattr(twin, name, getattr(good, name))
    twin.State = q_learning.State.__class__("State", (q_learning.State,), {})  # same name
    twin.init_state = lambda cfg, geom, rng: q_learning.init_state(cfg, geom, rng)
    with pytest.raises(ValueError, match=r"twin.State has the class name and the field types "
                                         r"of learning.methods.q_learning.State.*Give the class a "
                                         r"name of its own"):
        register(type("T", (good.Throwaway,), {"cli": "t"}), twin)


def test_the_package_methods_states_are_told_apart():
    from learning.methods.registry import FAMILY_OF_CONFIG, state_fingerprint

    seen: dict[bytes, str] = {}
    for config, module in FAMILY_OF_CONFIG.items():
        fp = state_fingerprint(config, module)
        assert seen.setdefault(fp, module.__name__) == module.__name__, config.cli


def test_register_says_what_is_wrong_with_a_method_module():
    import types

    from learning.methods.registry import register
    from tests import test_new_method as good

    plain = types.ModuleType("plainhooks")
    for name in ("State", "init_state", "update", "begin", "exploit"):
        setattr(plain, name, getattr(good, name))
    plain.act = lambda st, s, rng: 0
    with pytest.raises(ValueError, match=r"plainhooks.act is a plain Python function.*"
                                         r"@numba.njit"):
        register(type("P", (good.Throwaway,), {"cli": "p"}), plain)
    short = types.ModuleType("shorthooks")
    for name in ("State", "init_state", "act", "update", "begin", "exploit"):
        setattr(short, name, getattr(good, name))
    from numba import njit

    short.begin = njit(lambda st: None)
    with pytest.raises(ValueError, match=r"shorthooks.begin takes \(st\), but the loops call "
                                         r"it as begin\(st, s0\)"):
        register(type("S", (good.Throwaway,), {"cli": "s"}), short)
