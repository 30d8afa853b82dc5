"""Exact sums inside vectorised loops: a float rounded to a fixed quantum, as an int64.

The row kernels add, for each node they update, its share of the energy budget
(``kernels.budget``).  A float sum would depend on the order of the additions,
which depends on the rank count and the task order; an integer sum does not, and
a compiler vectorises it without being allowed to reassociate floats.  Each
value v is rounded to a multiple of its quantum 1/S by the magic-number trick
(v S + 1.5 2^52 keeps round(v S) in its low mantissa bits), a register move
and an integer subtraction: no float-to-int conversion, which this machine's
vector units lack.
"""
import numpy as np
from numba import njit, types
from numba.extending import intrinsic

# Terms summed over the nodes inside the row kernels, each an exact integer multiple of its own quantum 1/S
# (m c^2) per rank (``Budget.acc``, two int64 words: hi * 2^62 + lo): integer sums are associative, so they
# vectorise and are the same on any rank count and any task order.  A value is given already scaled, v S,
# and must stay below 2^51 in magnitude (``scales`` picks S so that it does for any node the runaway check
# lets pass); rounding it costs at most half a quantum per node and step.
Q_DAMP, Q_KIN, Q_EL = 0, 1, 2
N_Q = 3
MAGIC = 1.5 * 2.0 ** 52                 # w + MAGIC holds round(w) in its low mantissa bits, |w| < 2^51
MAGIC_BITS = int(np.array(MAGIC).view(np.int64))
WORD = 62                               # lo in [0, 2^62)


def scales(sd: float) -> np.ndarray:
    """S (1/m c^2) of each term, powers of two: the damping's so that a node moving 1 a in two steps (twice
    the runaway limit) stays within 2^50 quanta, sd = zeta/(4 dt) of the body drag, but no finer than 2^-50;
    the kinetic energy's to 128 m c^2 a node (a velocity of 16 c), the elastic's to 8192 (-1/2 u . F with u
    up to thousands of a)."""
    return np.array([2.0 ** np.floor(np.log2(2.0 ** 50 / max(sd, 1.0))), 2.0 ** 44, 2.0 ** 38])


@intrinsic
def _bits(typingctx, x):
    """The int64 with the bits of the float64 x (a register move, so a loop that uses it still vectorises)."""
    if x != types.float64:
        return None

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], context.get_value_type(types.int64))
    return types.int64(types.float64), codegen


@njit(cache=True, inline="always", _nrt=False)
def quant(w):
    """round(w) as an int64, for |w| < 2^51: one float addition and a register move."""
    return _bits(w + MAGIC) - MAGIC_BITS


