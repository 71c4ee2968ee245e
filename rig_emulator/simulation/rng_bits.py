"""The step loop's random generator, handed over as its bit generator (issue 14, cold compile).

numba unboxes a ``numpy.random.Generator`` argument into a struct holding a reference-counted
handle on the Python object (a meminfo): only a function compiled with numba's reference
counting (NRT) releases it, and the step loop is compiled without (``rig_emulator/_jit.py``).
It therefore used to be entered through a small NRT function that only called the loop, and
that wrapper cost about a tenth of the cold compile: numba links every callee into its
caller's LLVM module and optimises and compiles the whole again, so the wrapper compiled the
entire loop a second time.

A ``BitGenerator`` unboxes into plain pointers (no reference kept), so Python passes
``rng.bit_generator`` and :func:`generator` rebuilds numba's Generator value around it inside
the loop. Its other two fields (the Python object, the meminfo) stay null: only boxing the
Generator back to Python or reference counting read them, and the loop does neither. The
numbers drawn are those of ``rng`` itself (same bit generator, same state, advanced in place).
"""

from numba import types
from numba.core import cgutils
from numba.core.extending import intrinsic

_GENERATOR = types.NumPyRandomGeneratorType("generator")  # numba's type of every np.random.Generator


@intrinsic
def generator(typingctx, bits):
    """numba's ``np.random.Generator`` value over the bit generator ``bits``."""
    if not isinstance(bits, types.NumPyRandomBitGeneratorType):
        return None

    def codegen(context, builder, sig, args):
        gen = cgutils.create_struct_proxy(_GENERATOR)(context, builder)  # zero-filled
        gen.bit_generator = args[0]
        return gen._getvalue()

    return _GENERATOR(bits), codegen
