"""Generic operations on a learner's state, whatever the method: a named tuple whose fields
are arrays, named tuples of arrays, and ``par`` (the config's scalars).

Copying, flattening to dotted names (what checkpoints store), stacking N agents'
states along a new leading axis (the batch agent) and taking agent i's row of a
stack, in Python and in compiled code (:func:`row`).
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
from numba import types
from numba.extending import overload

PARAMS = "par"  # the field holding the config's scalars (not state: rebuilt from the config)


def _is_tree(x) -> bool:
    return isinstance(x, tuple) and hasattr(x, "_fields")


def arrays(st, prefix: str = "") -> Iterator[tuple[str, np.ndarray]]:
    """(dotted name, array) of every array in the state, in field order."""
    for name, v in zip(st._fields, st, strict=True):
        if name == PARAMS and not prefix:
            continue
        if _is_tree(v):
            yield from arrays(v, f"{prefix}{name}.")
        else:
            yield f"{prefix}{name}", v


def rebuild(st, fn):
    """The same tree with every array ``a`` replaced by ``fn(name, a)``."""
    def go(node, prefix):
        out = []
        for name, v in zip(node._fields, node, strict=True):
            if name == PARAMS and not prefix:
                out.append(v)
            elif _is_tree(v):
                out.append(go(v, f"{prefix}{name}."))
            else:
                out.append(fn(f"{prefix}{name}", v))
        return type(node)(*out)
    return go(st, "")


def copy_state(st):
    return rebuild(st, lambda _, a: a.copy())


def episodes_done(st) -> int:
    return int(st.tally.episode[0])


def stack(states: list):
    """N states of one method and geometry as one: each array gains a leading axis N."""
    first = states[0]
    flat = [dict(arrays(s)) for s in states]
    return rebuild(first, lambda name, _: np.ascontiguousarray(np.stack([f[name] for f in flat])))


def row_view(batch, i: int):
    """Agent i of a stacked state (views, so writes go to the stack)."""
    return rebuild(batch, lambda _, a: a[i])


def row(st, i):
    """Compiled: agent i of a stacked state (views)."""
    raise NotImplementedError("compiled code only; from Python call row_view()")


@overload(row)
def _row(st, i):
    """Generates ``cls(st.a[i], row(st.sub, i), ..., st.par)`` for the state's type."""
    if not isinstance(st, types.BaseNamedTuple):
        return None
    parts = []
    for name, t in zip(st.fields, st.types, strict=True):
        if isinstance(t, types.Array):
            parts.append(f"st.{name}[i]")
        elif isinstance(t, types.BaseNamedTuple) and name != PARAMS:
            parts.append(f"row(st.{name}, i)")
        else:
            parts.append(f"st.{name}")
    src = f"def impl(st, i):\n    return cls({', '.join(parts)})\n"
    ns = {"cls": st.instance_class, "row": row}
    exec(src, ns)
    return ns["impl"]
