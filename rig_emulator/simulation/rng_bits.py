"""The step loop's random generator, handed over as its bit generator's pointers (less to
compile, and less to pay each time the loop is entered).

numba unboxes a ``numpy.random.Generator`` argument into a struct holding a reference-counted
handle on the Python object (a meminfo): only a function compiled with numba's reference
counting (NRT) releases it, and the step loop is compiled without (``rig_emulator/_jit.py``).
It therefore used to be entered through a small NRT function that only called the loop, and
that wrapper cost about a tenth of the cold compile: numba links every callee into its
caller's LLVM module and optimises and compiles the whole again, so the wrapper compiled the
entire loop a second time.

A ``BitGenerator`` unboxes into plain pointers (no reference kept), but numba finds them anew
at every call through Python: the ``ctypes`` attribute, an import of ``ctypes`` and three
``ctypes.cast`` calls, about 4 us a call, a third of entering the loop (the PX4 lockstep enters
it 250 times a simulated second). :func:`pointers` reads those pointers once, as five integers
(:data:`POINTER_FIELDS`), and :func:`generator` rebuilds numba's Generator value around them
inside the loop (from a BitGenerator too, as before). The Generator's other two fields (the
Python object, the meminfo) and the BitGenerator's Python object stay null: only boxing back
to Python or reference counting read them, and the loop does neither. The numbers drawn are
those of ``rng`` itself (same bit generator, same state, advanced in place). The integers are
valid while the bit generator lives: the caller keeps it (``Simulation._rng_pointers``).
"""

from numba import types
from numba.core import cgutils
from numba.core.extending import intrinsic

_GENERATOR = types.NumPyRandomGeneratorType("generator")  # numba's type of every np.random.Generator
_BIT_GENERATOR = types.NumPyRandomBitGeneratorType("bit_generator")
#: what :func:`pointers` returns, in this order (fields of numba's BitGenerator struct)
POINTER_FIELDS = ("state_address", "state", "fnptr_next_uint64", "fnptr_next_uint32", "fnptr_next_double")


def pointers(bit_generator) -> tuple:
    """The five integers of :data:`POINTER_FIELDS` of a ``numpy.random.BitGenerator``: what
    numba's own unboxing reads from its ``ctypes`` interface (``numba/core/boxing.py``)."""
    import ctypes

    c = bit_generator.ctypes
    fn = [ctypes.cast(f, ctypes.c_void_p).value for f in (c.next_uint64, c.next_uint32, c.next_double)]
    return (int(c.state_address), int(c.state.value), *(int(v) for v in fn))


@intrinsic
def generator(typingctx, bits):
    """numba's ``np.random.Generator`` value over ``bits``: a bit generator, or its
    :func:`pointers`."""
    if isinstance(bits, types.NumPyRandomBitGeneratorType):
        def codegen(context, builder, sig, args):
            gen = cgutils.create_struct_proxy(_GENERATOR)(context, builder)  # zero-filled
            gen.bit_generator = args[0]
            return gen._getvalue()

        return _GENERATOR(bits), codegen
    if isinstance(bits, types.UniTuple) and bits.count == len(POINTER_FIELDS) and isinstance(bits.dtype, types.Integer):
        def codegen(context, builder, sig, args):
            bitgen = cgutils.create_struct_proxy(_BIT_GENERATOR)(context, builder)  # zero-filled: no parent
            for i, name in enumerate(POINTER_FIELDS):
                value = context.cast(builder, builder.extract_value(args[0], i), bits.dtype, types.uintp)
                setattr(bitgen, name, value)
            gen = cgutils.create_struct_proxy(_GENERATOR)(context, builder)
            gen.bit_generator = bitgen._getvalue()
            return gen._getvalue()

        return _GENERATOR(bits), codegen
    return None
