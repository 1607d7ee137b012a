"""A learner's named state behind one reference, for callers that cross into compiled code
once per event.

Passing a named tuple of arrays from Python into a compiled function unboxes every
array on every call: ~10 us a call for RNH-QL+'s ~40 arrays, more than the event
costs. A :class:`StateBox` holds the state on numba's side; a call then unboxes one
reference (~1.4 us a call, measured on ``paper-50``), and compiled code reads
``box.state``. The box holds the same arrays as the Python state (no copy), so
Python reads and writes through either see each other.
"""

from __future__ import annotations

from numba import njit, types
from numba.experimental import structref


@structref.register
class StateBoxType(types.StructRef):
    def preprocess_fields(self, fields):
        return tuple((name, types.unliteral(typ)) for name, typ in fields)


class StateBox(structref.StructRefProxy):
    """One learner's state on numba's side; build it with :func:`box_of`."""


structref.define_proxy(StateBox, StateBoxType, ["state"])


@njit(cache=True)
def box_of(st):
    """A :class:`StateBox` holding ``st`` (the same arrays)."""
    return StateBox(st)
