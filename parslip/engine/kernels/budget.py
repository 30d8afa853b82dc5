"""The energy budget's arithmetic: running totals kept in two floats, and the state's energy at a frame.

Damped Verlet conserves, without damping and external forces, the staggered energy of the half step
n - 1/2 (m = 1, u in a, dt in a/c, energies in m c^2)

    H(n - 1/2) = |u(n) - u(n-1)|^2 / (2 dt^2) + 1/2 u(n-1)^T K u(n)       (kinetic + elastic)

with K the bulk and interface bonds as they stand between the steps n - 1 and n (for an interface
bond, 1/2 [k_x (x_ij(n-1) - x0)(x_ij(n) - x0) + k_y (y_ij(n-1) - delta0)(y_ij(n) - delta0)]).  A step n
changes it by exactly

    f(n) . (u(n+1) - u(n-1)) / 2                   the work of an external force (drive, F_N)
    - zeta |u(n+1) - u(n-1)|^2 / (4 dt)             the body drag ("absolute"), per node
    + 1/2 [C F(z) - C F(u)] . (u(n+1) - u(n-1)) / C the bonds' dashpots ("bonds": z - u = g (u(n) - u(n-1)))
    - the staggered energy of the bonds the step broke, + that of those it re-formed
    - the staggered energy of the contact springs the step switched off, + that of those it switched on
    - 1/2 (k(n-1) - k(n)) s(n-1) s(n) of each weakening bond, whose shear stiffness the step lowered
      (``interface.softening``: a bond of stiffness k(n) in step n is a spring re-formed each step)
    - k_c p (e(n-1) + e(n))/2 per site in contact with friction (``interface.contact_friction``): its stick
      spring 1/2 k_c (xi - a)^2 along the surface, of stretch e = xi - a, slips by p past it (its anchor a
      moves); the springs it replaces are switched as the contact springs are

(``tests/test_energy_budget.py`` proves these forms from outside the engine).

The contact (``interface.contact``).  A free site's contact force at step n, f = k_c (delta0 - d) n on the
top node and -(1 - w) f, -w f on the substrate sites q, q + 1 (``kernels.interface._contacts``), is that of
a linear spring whose geometry (q, the normal n, the weight w) is read off u(n): its compression
s(u) = delta0 - n . (r(u) - w e(u)) is affine in the three nodes' displacements and equals delta0 - d at
u(n), and f = -grad 1/2 k_c s^2 exactly (w clipped or not).  So each step sets up a contact spring from
u(n), as if the step re-formed it, and the budget counts it the way it counts an interface bond: its
staggered energy 1/2 k_c s(u(n-1)) s(u(n)) is part of H (the term CONTACT), and a step that replaces the
springs of u(n-1) by those of u(n) adds, per site, the new spring's staggered energy at (u(n-1), u(n)) less
the old one's (the term SWITCHED).  Where a site gains or loses its contact (its bond breaks or re-forms, d
crosses delta0) one of the two is absent; where it keeps it, their difference is what the surface's
turning and the site's sliding along it change, and what a change of segment (a kink of the surface)
makes appear or vanish.  The one-sided spring's own energy 1/2 k_c (delta0 - d)^2 is continuous at d =
delta0; its staggered form is not, by O(k_c s ds).

The loop adds the per-step terms as they happen, each to a running total of its own unit (the damping to
a column of its block, the drive's work to a driven node, breaks, re-formations, the contacts' switches,
the bonds' weakening and the contact's friction to an interface site: ``SITE_TERMS``), and evaluates the state terms at every interface frame
(``loop._energies``).  A new interface term (friction, softening) is one more index below, one more row of
``SITE_TERMS`` if it is a running total per site, and one more dataset of ``io.contract.ENERGY_DATASETS``.

Rank invariance.  A column's nodes are updated by tasks whose order depends on the rank count, so a
plain running sum would round differently on 1 and 3 ranks.  Every total is therefore a pair of
floats (hi, lo) grown by an error-free two-sum: hi + lo holds the exact sum to about 2^-106 of its
size, whatever the order; rank 0 adds all pairs with ``math.fsum`` (correctly rounded), so the
written value is the same bits on any rank count unless the exact sum lies within ~1e-30 of a
rounding boundary.
"""
from numba import njit

from .exact import N_Q, Q_DAMP, Q_EL, Q_KIN, WORD  # noqa: F401  (the kernels' exact sums)

from .stencil import DL_, DR_, L_, R_, UL_, UR_

# A running total's two floats: row HI and row LO of an accumulator array [2, units].
HI, LO = 0, 1
# The terms a frame records, each as (hi, lo) of this rank's share (``loop.Frames.energy``):
#   W_DRIVE, DAMPING, BROKEN, FORMED   totals since the drive started (m c^2)
#   KINETIC, ELASTIC                   H(n - 1/2)'s two parts at the frame's step n (m c^2)
#   LOAD_Y                             sum over the loaded nodes of u_y(n) + u_y(n-1) (a): the load's work
#                                      since the drive started is f_N/2 times its change (F_N is constant
#                                      by then, so sum_m f (u(m+1) - u(m-1))/2 telescopes)
#   CONTACT                            the contact springs' staggered energy at the frame's step n (m c^2)
#   SWITCHED                           total since the drive started of what the contacts' switches added
#   SOFTENED                           total since the drive started of what the bonds' weakening took
#   FRICTION                           total since the drive started of what the contact's friction took
W_DRIVE, DAMPING, BROKEN, FORMED, KINETIC, ELASTIC, LOAD_Y, CONTACT, SWITCHED, SOFTENED, FRICTION = range(11)
N_TERMS = 11
RUNNING = (W_DRIVE, DAMPING, BROKEN, FORMED, SWITCHED, SOFTENED, FRICTION)
# The state's terms, written as their change since the drive started (their values there: ``STATE``'s order).
STATE = (KINETIC, ELASTIC, LOAD_Y, CONTACT)
# The running totals kept per interface site (local column of the block's interface row), the rows of
# ``loop.Budget.sites`` [row, HI|LO, site]: row S_BROKEN holds term SITE_TERMS[S_BROKEN], and so on.
SITE_TERMS = (BROKEN, FORMED, SWITCHED, SOFTENED, FRICTION)
S_BROKEN, S_FORMED, S_SWITCHED, S_SOFTENED, S_FRICTION = range(5)

# Bond masks of the row kinds (``parallel.layout``): FULL, NO_UP (top row), NO_DOWN (bottom row).
ALL = R_ | UR_ | UL_ | L_ | DL_ | DR_
NO_UP_MASK = R_ | L_ | DL_ | DR_
NO_DOWN_MASK = R_ | L_ | UR_ | UL_


@njit(cache=True, forceinline=True, _nrt=False)
def deposit(acc, q, x):
    """acc[q] (hi, lo: the integer hi * 2^62 + lo, lo in [0, 2^62)) += x, exactly."""
    lo = acc[q, 1] + x
    carry = lo >> WORD
    acc[q, 0] += carry
    acc[q, 1] = lo - (carry << WORD)


@njit(cache=True, forceinline=True, _nrt=False)
def exact_parts(acc, q, scale, out, k):
    """out[2:5, k] = three floats whose exact sum is acc[q] / scale[q] (each part exact: the quanta's two
    words cut into pieces of at most 31 bits, times a power of two)."""
    inv = 1.0 / scale[q]
    lo = acc[q, 1]
    out[2, k] = float(acc[q, 0]) * (2.0 ** WORD) * inv
    out[3, k] = float(lo >> 31) * (2.0 ** 31) * inv
    out[4, k] = float(lo & ((1 << 31) - 1)) * inv


# Inlined by numba: the step's kernels and the frames' call it, and a job compiles those on two ranks at
# once (engine.compile); compiled on its own, both would compile it.
@njit(cache=True, inline="always", _nrt=False)
def add(acc, i, v):
    """acc[HI, i] + acc[LO, i] += v without losing a bit (Knuth's two-sum; no FMA can enter it)."""
    a = acc[HI, i]
    s = a + v
    bp = s - a
    err = (a - (s - bp)) + (v - bp)
    acc[HI, i] = s
    acc[LO, i] += err


@njit(cache=True, _nrt=False)
def total(acc, out, k):
    """out[k] (a pair) += the sum of every unit of ``acc``, kept as a pair."""
    for i in range(acc.shape[1]):
        add(out, k, acc[HI, i])
        add(out, k, acc[LO, i])


@njit(cache=True, _nrt=False)
def load_sum(cy, oy, r, j0, n, out):
    """out[LOAD_Y] += sum over the segment of u_y(n) + u_y(n-1)."""
    for k in range(n):
        add(out, LOAD_Y, float(cy[r, j0 + k]) + float(oy[r, j0 + k]))


# Inlined by numba: the step's kernels and the frames' call it, and a job compiles those on two ranks at
# once (engine.compile); compiled on its own, both would compile it.
@njit(cache=True, inline="always", _nrt=False)
def bond_energy(kx, ky, sx0, sy0, sx1, sy1):
    """An interface bond's staggered energy 1/2 [k_x s_x(n-1) s_x(n) + k_y s_y(n-1) s_y(n)], s its stretch
    (x_ij - x0, y_ij - delta0) at the two levels."""
    return 0.5 * (float(kx) * float(sx0) * float(sx1) + float(ky) * float(sy0) * float(sy1))


# Inlined by numba: the step's kernels and the frames' call it, and a job compiles those on two ranks at
# once (engine.compile); compiled on its own, both would compile it.
@njit(cache=True, inline="always", _nrt=False)
def contact_energy(kc, s0, s1):
    """A contact spring's staggered energy 1/2 k_c s(n-1) s(n), s its compression at the two levels (a)."""
    return 0.5 * float(kc) * float(s0) * float(s1)
