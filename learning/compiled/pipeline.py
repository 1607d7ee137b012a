"""The training templates' compiler: numba's own, plus one pass that drops the copies of
arguments that inlining leaves behind.

Why: numba inlines a hook (``inline="always"``) by assigning each argument at the call
site to the hook's parameter, ``st.1 = st``. Assigning a named tuple of arrays takes a
reference to every array in it, and the copy dies at the end of the hook: two atomic
operations per array per call. The rnh-ql+ state holds about thirty arrays and the step
calls two hooks, so a step paid about 120 of them before any work, which LLVM's
reference-count pruning cannot remove because the hooks branch and call out (measured
with ``perf``: ``NRT_incref``/``NRT_decref`` took 23 % of an ``rnh-ql+`` run on a 512²
maze, BENCHMARKS.md). Python's own semantics make the copy an alias, so using the
argument itself is the same program: the pass replaces every use of a variable defined
once as a copy of another variable defined once, and deletes the copy.
"""

from __future__ import annotations

from collections import defaultdict

from numba.core import ir
from numba.core.compiler import CompilerBase, DefaultPassBuilder
from numba.core.compiler_machinery import FunctionPass, register_pass
from numba.core.ir_utils import replace_vars
from numba.core.untyped_passes import InlineInlinables


def _single_copies(blocks) -> dict[str, ir.Var]:
    """{name: the variable it copies} for every variable assigned exactly once, from a
    variable also assigned exactly once (or an argument, assigned once by definition),
    followed through chains of copies to the first."""
    defs: dict[str, list[ir.Assign]] = {}
    for block in blocks.values():
        for stmt in block.body:
            if isinstance(stmt, ir.Assign):
                defs.setdefault(stmt.target.name, []).append(stmt)
    copies: dict[str, ir.Var] = {}
    for name, assigns in defs.items():
        if len(assigns) != 1 or not isinstance(assigns[0].value, ir.Var):
            continue
        source = assigns[0].value
        if len(defs.get(source.name, ())) == 1:
            copies[name] = source
    for name in copies:
        seen = {name}
        source = copies[name]
        while source.name in copies and source.name not in seen:
            seen.add(source.name)
            source = copies[source.name]
        copies[name] = source
    return copies


def _drop_copies(blocks) -> bool:
    """Use the original variable in place of each single copy of a single variable
    (:func:`_single_copies`), and delete the copy (and its ``del``)."""
    copies = _single_copies(blocks)
    if not copies:
        return False
    for block in blocks.values():
        block.body = [stmt for stmt in block.body
                      if not (isinstance(stmt, ir.Assign) and stmt.target.name in copies)
                      and not (isinstance(stmt, ir.Del) and stmt.value in copies)]
    replace_vars(blocks, copies)
    return True


def _hoist_state_reads(func_ir, blocks, root: str) -> bool:
    """Read each field (and field of a field) of the argument ``root`` once, at the top of
    the function, and make every read of it in the body a copy of that one (which
    :func:`_drop_copies` then removes). A named tuple is immutable and the argument is
    never reassigned (checked), so a read is the same value wherever it is made."""
    entry = blocks[min(blocks)]
    args = [stmt for stmt in entry.body
            if isinstance(stmt, ir.Assign) and isinstance(stmt.value, ir.Arg)
            and stmt.value.name == root]
    defs = _definitions(blocks)
    if len(args) != 1 or len(defs[root]) != 1:
        return False
    scope, loc = entry.scope, args[0].loc
    hoisted: dict[tuple[str, ...], ir.Var] = {(): args[0].target}
    paths: dict[str, tuple[str, ...]] = {root: ()}  # variable -> the field path it reads
    reads: list[tuple[ir.Assign, tuple[str, ...]]] = []
    changed = True
    while changed:  # fields of fields: follow reads of reads until none is new
        changed = False
        for block in blocks.values():
            for stmt in block.body:
                if (isinstance(stmt, ir.Assign) and isinstance(stmt.value, ir.Expr)
                        and stmt.value.op == "getattr" and stmt.value.value.name in paths
                        and stmt.target.name not in paths
                        and len(defs[stmt.target.name]) == 1):
                    path = paths[stmt.value.value.name] + (stmt.value.attr,)
                    paths[stmt.target.name] = path
                    reads.append((stmt, path))
                    changed = True
    if not reads:
        return False
    top: list[ir.Assign] = []
    for _, path in sorted(reads, key=lambda r: len(r[1])):
        if path not in hoisted:
            var = scope.redefine(f"state_{'_'.join(path)}", loc)
            top.append(ir.Assign(ir.Expr.getattr(hoisted[path[:-1]], path[-1], loc), var,
                                 loc))
            hoisted[path] = var
    for stmt, path in reads:
        stmt.value = hoisted[path]
    at = entry.body.index(args[0]) + 1
    entry.body[at:at] = top
    return True


@register_pass(mutates_CFG=False, analysis_only=False)
class DropInlinedCopies(FunctionPass):
    """:func:`_drop_copies`, then :func:`_hoist_state_reads` of the state ``st`` and
    :func:`_drop_copies` again for the copies that leaves."""

    _name = "drop_inlined_copies"

    def __init__(self):
        FunctionPass.__init__(self)

    def run_pass(self, state):
        blocks = state.func_ir.blocks
        changed = _drop_copies(blocks)
        if _hoist_state_reads(state.func_ir, blocks, "st"):
            _drop_copies(blocks)
            changed = True
        if changed:
            state.func_ir._definitions = _definitions(blocks)
        return changed


def _definitions(blocks) -> dict:
    """What numba's ``func_ir._definitions`` holds: each variable's assigned values."""
    out: defaultdict = defaultdict(list)
    for block in blocks.values():
        for stmt in block.body:
            if isinstance(stmt, ir.Assign):
                out[stmt.target.name].append(stmt.value)
    return out


class TemplateCompiler(CompilerBase):
    """numba's nopython pipeline with :class:`DropInlinedCopies` right after inlining."""

    def define_pipelines(self):
        pm = DefaultPassBuilder.define_nopython_pipeline(self.state)
        pm.add_pass_after(DropInlinedCopies, InlineInlinables)
        pm.finalize()
        return [pm]
