"""The training templates' compiler (learning.compiled.pipeline): reads of the state hoisted
to the top and inlined copies dropped give the same program, and only where that is safe."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit
from numba.core import ir
from numba.core.compiler import run_frontend

from learning.compiled.pipeline import TemplateCompiler, _drop_copies, _hoist_state_reads


class Inner(NamedTuple):
    a: np.ndarray
    b: np.ndarray


class Box(NamedTuple):
    k: float
    inner: Inner
    c: np.ndarray


@njit(inline="always")
def _hook(st, i):
    """Reads in branches and a nested read, as the methods' hooks do."""
    inner = st.inner
    if i % 3 == 0:
        st.inner.a[i % inner.a.shape[0]] += st.k
    elif i % 3 == 1:
        inner.b[0] += st.c[i % st.c.shape[0]]
    return st.inner.a.sum() + st.c[0]


def _template(st, n):
    total = 0.0
    for i in range(n):
        total += _hook(st, i)
    return total


def _reassigning(st, n):
    total = 0.0
    for _i in range(n):
        total += st.k
        st = Box(st.k + 1.0, st.inner, st.c)
    return total


def _box() -> Box:
    return Box(0.5, Inner(np.arange(4.0), np.zeros(2)), np.array([1.0, 2.0, 3.0]))


def test_the_template_compiler_gives_numbas_results():
    plain = njit(_template)
    ours = njit(pipeline_class=TemplateCompiler)(_template)
    one, two = _box(), _box()
    assert plain(one, 50) == ours(two, 50)
    np.testing.assert_array_equal(one.inner.a, two.inner.a)
    np.testing.assert_array_equal(one.inner.b, two.inner.b)
    assert njit(_reassigning)(_box(), 5) == njit(pipeline_class=TemplateCompiler)(
        _reassigning)(_box(), 5) == 0.5 + 1.5 + 2.5 + 3.5 + 4.5


def _getattrs_on_state(func_ir) -> dict[int, int]:
    """{block label: reads of st's fields, or of fields of them, in it}."""
    names = {"st"}
    counts: dict[int, int] = {}
    for label, block in func_ir.blocks.items():
        for stmt in block.body:
            if (isinstance(stmt, ir.Assign) and isinstance(stmt.value, ir.Expr)
                    and stmt.value.op == "getattr" and stmt.value.value.name in names):
                names.add(stmt.target.name)
                counts[label] = counts.get(label, 0) + 1
    return counts


def test_reads_of_the_state_move_to_the_entry_block_once_each():
    func_ir = run_frontend(_reassigning_free_loop)
    before = _getattrs_on_state(func_ir)
    assert sum(before.values()) == 6 and set(before) != {min(func_ir.blocks)}
    assert _hoist_state_reads(func_ir, func_ir.blocks, "st")
    _drop_copies(func_ir.blocks)
    after = _getattrs_on_state(func_ir)
    assert after == {min(func_ir.blocks): 3}  # st.k, st.inner, st.inner.a: each once


def _reassigning_free_loop(st, n):
    total = 0.0
    for i in range(n):
        total += st.k + st.inner.a[0]
        if i > 2:
            total += st.k * st.inner.a[1]
    return total


def test_a_reassigned_state_is_left_alone():
    func_ir = run_frontend(_reassigning)
    assert not _hoist_state_reads(func_ir, func_ir.blocks, "st")
