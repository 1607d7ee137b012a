"""The training templates' compiler (learning.compiled.pipeline): reads of the state hoisted
to the top and inlined copies dropped give the same program, and only where that is safe."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit
from numba.core import ir
from numba.core.compiler import DefaultPassBuilder
from numba.core.compiler_machinery import FunctionPass, register_pass
from numba.core.typed_passes import InlineOverloads

from learning.compiled.pipeline import ReadTuplesOnce, TemplateCompiler


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


SEEN: list = []


@register_pass(mutates_CFG=False, analysis_only=True)
class _Keep(FunctionPass):
    """Keeps the IR as the pass left it, for the tests to read."""

    _name = "keep_ir_for_tests"

    def __init__(self):
        FunctionPass.__init__(self)

    def run_pass(self, state):
        SEEN.append(state.func_ir.copy())
        return False


class _Watched(TemplateCompiler):
    def define_pipelines(self):
        pm = DefaultPassBuilder.define_nopython_pipeline(self.state)
        pm.add_pass_after(ReadTuplesOnce, InlineOverloads)
        pm.add_pass_after(_Keep, ReadTuplesOnce)
        pm.finalize()
        return [pm]


def _reads_of(func_ir, root: str) -> dict[int, int]:
    """{block label: reads of ``root``'s fields (any of its SSA versions: ``st``, ``st.1``),
    or of fields of them, in it}."""
    names = {v for v in func_ir._definitions if v == root or v.startswith(root + ".")}
    counts: dict[int, int] = {}
    for label in sorted(func_ir.blocks):
        for stmt in func_ir.blocks[label].body:
            if (isinstance(stmt, ir.Assign) and isinstance(stmt.value, ir.Expr)
                    and stmt.value.op == "getattr" and stmt.value.value.name in names):
                names.add(stmt.target.name)
                counts[label] = counts.get(label, 0) + 1
    return counts


def _loop(st, n):
    total = 0.0
    for i in range(n):
        total += st.k + st.inner.a[0]
        if i > 2:
            total += st.k * st.inner.a[1]
    return total


def test_reads_of_the_state_move_to_the_entry_block_once_each():
    SEEN.clear()
    assert njit(pipeline_class=_Watched)(_loop)(_box(), 5) == njit(_loop)(_box(), 5)
    func_ir = SEEN[-1]
    assert _reads_of(func_ir, "st") == {min(func_ir.blocks): 3}  # k, inner, inner.a


def test_a_reassigned_state_is_read_where_it_was():
    SEEN.clear()
    njit(pipeline_class=_Watched)(_reassigning)(_box(), 5)
    func_ir = SEEN[-1]
    reads = _reads_of(func_ir, "st")
    assert sum(reads.values()) >= 1 and set(reads) != {min(func_ir.blocks)}
