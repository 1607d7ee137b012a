"""A ``numpy.random.Generator`` passed to compiled code as six integers (the physics kernel's
copy of :mod:`learning.compiled.generator_handle`: ``sim`` and ``learning`` import nothing of
each other; a test holds the two equal, function by function).

Numba unboxes a ``Generator`` argument through ctypes on every call (16 us a call here).
A robot's wheel noise is refilled in compiled code, thousands of times in a graded run,
so the batch keeps each robot's generator as :func:`handle` and the compiled refill
rebuilds numba's Generator value from it (:func:`generator_from`): the generator's own
state and functions, so its stream continues exactly as if it had been passed.

The handle does not own the generator: keep the Generator object alive while its handle
is used (the batch holds both).
"""

from __future__ import annotations

import ctypes

import numpy as np
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

HANDLE_SIZE = 6


def handle(rng: np.random.Generator) -> np.ndarray:
    """uint64[6]: state address, state, next_uint64, next_uint32, next_double, bit generator."""
    ct = rng.bit_generator.ctypes

    def address(fn: object) -> int:
        return int(ctypes.cast(fn, ctypes.c_void_p).value or 0)

    return np.array([ct.state_address, ct.state.value or 0, address(ct.next_uint64),
                     address(ct.next_uint32), address(ct.next_double),
                     ct.bit_generator.value or 0], dtype=np.uint64)


def handles(rngs: list[np.random.Generator]) -> np.ndarray:
    """uint64[n, 6]: one :func:`handle` per generator."""
    return np.stack([handle(r) for r in rngs]) if rngs else np.zeros((0, HANDLE_SIZE),
                                                                      np.uint64)


_GENERATOR = types.NumPyRandomGeneratorType("generator")
_BIT_GENERATOR = types.NumPyRandomBitGeneratorType("bit_generator")


@intrinsic
def generator_from(typingctx, h):
    """Compiled code only: numba's Generator value for the handle ``h`` (uint64[6])."""
    if not (isinstance(h, types.Array) and h.dtype == types.uint64 and h.ndim == 1):
        return None
    sig = _GENERATOR(h)

    def codegen(context, builder, signature, args):
        arr = context.make_array(signature.args[0])(context, builder, args[0])

        def word(k):
            return builder.load(builder.gep(arr.data, [context.get_constant(types.intp, k)]))

        bit = cgutils.create_struct_proxy(_BIT_GENERATOR)(context, builder)
        bit.state_address = word(0)
        bit.state = word(1)
        bit.fnptr_next_uint64 = word(2)
        bit.fnptr_next_uint32 = word(3)
        bit.fnptr_next_double = word(4)
        bit.bit_generator = word(5)
        bit.parent = cgutils.get_null_value(context.get_value_type(types.pyobject))
        gen = cgutils.create_struct_proxy(_GENERATOR)(context, builder)
        gen.bit_generator = bit._getvalue()
        gen.meminfo = cgutils.get_null_value(
            context.get_value_type(types.MemInfoPointer(types.voidptr)))
        gen.parent = cgutils.get_null_value(context.get_value_type(types.pyobject))
        return gen._getvalue()

    return sig, codegen
