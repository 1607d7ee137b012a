"""The hot loops' compiler: numba's own, plus one pass that reads each field of a named
tuple once and drops the copies that inlining leaves behind.

Why: numba takes a reference (an atomic add, and an atomic subtract when it dies) to every
array it reads out of a named tuple, at every read, and to every array of a tuple it copies.
Inlining a hook (``inline="always"``, or an ``overload``) assigns each argument at the call
site to the hook's parameter (``st.1 = st``: a reference to each of the state's thirty-odd
arrays), and the hook then reads the fields it needs, again at every call. LLVM's
reference-count pruning cannot remove these counts where the hooks branch and call out.
Measured with ``perf`` (BENCHMARKS.md): ``NRT_incref``/``NRT_decref`` took 23 % of an
``rnh-ql+`` run on a 512² maze, and two thirds of the fused physics learning run.

A named tuple is immutable, so a field read right after the tuple is defined is the same
value wherever the program reads it, and a copy of a variable assigned once is the variable
itself. The pass (after typing, so it knows which values are named tuples, and after the
typed inliner, so it sees the overloads' bodies too):

* drops each copy ``x = y`` of a variable assigned once to a variable assigned once, of
  the same type, using ``y`` wherever ``x`` was used;
* moves each read of a named tuple's field to just after the tuple's one definition (a
  read of a field of that, after it, and so on), one read per field: a loop that reads
  the state's arrays at every step then takes each reference once, before the loop.
"""

from __future__ import annotations

from collections import defaultdict
from types import FunctionType

from numba import njit
from numba.core import ir, types
from numba.core.analysis import compute_cfg_from_blocks
from numba.core.compiler import CompilerBase, DefaultPassBuilder
from numba.core.compiler_machinery import FunctionPass, register_pass
from numba.core.ir_utils import build_definitions, replace_vars
from numba.core.typed_passes import InlineOverloads


def _settled(blocks) -> set[str]:
    """The variables assigned once whose assignment comes before every use on every path
    (it dominates them): in a loop, such a variable is never read before this iteration
    assigned it, so at any use it and whatever it was computed from hold this iteration's
    values. Only these are rewritten; a variable read before its assignment in a later
    iteration (a value carried round the loop) is left as it is."""
    dominators = compute_cfg_from_blocks(blocks).dominators()
    defined: dict[str, tuple[int, int]] = {}
    count: dict[str, int] = defaultdict(int)
    for label, block in blocks.items():
        for k, stmt in enumerate(block.body):
            if isinstance(stmt, ir.Assign):
                defined[stmt.target.name] = (label, k)
                count[stmt.target.name] += 1
    settled = {name for name, n in count.items() if n == 1}
    for label, block in blocks.items():
        for k, stmt in enumerate(block.body):
            if isinstance(stmt, ir.Assign):
                value = stmt.value
                used = ([value] if isinstance(value, ir.Var) else
                        value.list_vars() if isinstance(value, ir.Expr) else [])
            else:
                used = stmt.list_vars()
            for var in used:
                if var.name in settled:
                    at, j = defined[var.name]
                    if at not in dominators[label] or (at == label and j >= k):
                        settled.discard(var.name)
    return settled


def _drop_copies(blocks, typemap) -> bool:
    """Use ``y`` for ``x`` wherever a variable ``x`` is a copy of a variable ``y`` of the
    same type, both :func:`_settled`; delete the copy."""
    defs = build_definitions(blocks)
    settled = _settled(blocks)
    copies: dict[str, ir.Var] = {}
    for name, values in defs.items():
        if name in settled and isinstance(values[0], ir.Var):
            source = values[0]
            if source.name in settled and typemap[name] == typemap[source.name]:
                copies[name] = source
    if not copies:
        return False
    for name in copies:  # through chains of copies to the first
        seen, source = {name}, copies[name]
        while source.name in copies and source.name not in seen:
            seen.add(source.name)
            source = copies[source.name]
        copies[name] = source
    for block in blocks.values():
        block.body = [stmt for stmt in block.body
                      if not (isinstance(stmt, ir.Assign) and stmt.target.name in copies)
                      and not (isinstance(stmt, ir.Del) and stmt.value in copies)]
    replace_vars(blocks, copies)
    return True


def _hoist_tuple_reads(blocks, typemap) -> bool:
    """Move each read ``x = t.f`` of a named tuple ``t`` assigned once (into ``x`` assigned
    once) to just after ``t``'s definition; a second read of the same field becomes a copy
    of the first (which :func:`_drop_copies` removes). Reads of a read's fields follow it.
    Both variables must be :func:`_settled`. Statements are matched by identity: numba's
    IR compares them by value, slowly."""
    single = _settled(blocks)
    definition: dict[str, ir.Assign] = {}
    for block in blocks.values():
        for stmt in block.body:
            if isinstance(stmt, ir.Assign) and stmt.target.name in single:
                definition[stmt.target.name] = stmt
    first: dict[tuple[str, str], ir.Assign] = {}
    after: dict[int, list[ir.Assign]] = defaultdict(list)  # id(definition) -> reads moved
    moved: set[int] = set()
    changed = False
    for block in blocks.values():
        for stmt in block.body:
            if not (isinstance(stmt, ir.Assign) and isinstance(stmt.value, ir.Expr)
                    and stmt.value.op == "getattr"):
                continue
            tup = stmt.value.value.name
            if (stmt.target.name not in single or tup not in definition
                    or not isinstance(typemap[tup], types.BaseNamedTuple)):
                continue
            key = (tup, stmt.value.attr)
            read = first.get(key)
            if read is None:
                first[key] = stmt
                after[id(definition[tup])].append(stmt)
                moved.add(id(stmt))
            elif typemap[read.target.name] == typemap[stmt.target.name]:
                stmt.value = read.target  # a copy of the first read
                changed = True

    def emit(stmt, body):
        body.append(stmt)
        for read in after.get(id(stmt), ()):
            emit(read, body)

    for block in blocks.values():
        body: list = []
        for stmt in block.body:
            if id(stmt) not in moved:
                emit(stmt, body)
        changed = changed or [id(x) for x in body] != [id(x) for x in block.body]
        block.body = body
    return changed


@register_pass(mutates_CFG=False, analysis_only=False)
class ReadTuplesOnce(FunctionPass):
    """:func:`_drop_copies` and :func:`_hoist_tuple_reads` in turn until neither changes
    anything (at most 8 rounds)."""

    _name = "read_tuples_once"

    def __init__(self):
        FunctionPass.__init__(self)

    def run_pass(self, state):
        blocks, typemap = state.func_ir.blocks, state.typemap
        changed = False
        for _ in range(8):  # a dropped copy can make reads of it reads of the original
            if not (_drop_copies(blocks, typemap) | _hoist_tuple_reads(blocks, typemap)):
                break
            changed = True
        if changed:
            state.func_ir._definitions = build_definitions(blocks)
        return changed


class TemplateCompiler(CompilerBase):
    """numba's nopython pipeline with :class:`ReadTuplesOnce` right after the typed
    inliner."""

    def define_pipelines(self):
        pm = DefaultPassBuilder.define_nopython_pipeline(self.state)
        pm.add_pass_after(ReadTuplesOnce, InlineOverloads)
        pm.finalize()
        return [pm]


def read_once(fn, **jit):
    """The njit function ``fn`` compiled again by :class:`TemplateCompiler`, for a hot loop
    of a package that cannot import this one (``sim``): a copy under its own name (so
    numba's cache files of the two never meet), called by a caller here instead of ``fn``."""
    py = fn.py_func
    copy = FunctionType(py.__code__, py.__globals__, py.__name__, py.__defaults__,
                        py.__closure__)
    copy.__qualname__ = f"{py.__qualname__}_read_once"
    copy.__module__, copy.__doc__ = py.__module__, py.__doc__
    return njit(pipeline_class=TemplateCompiler, **jit)(copy)
