"""Sums over every rank that give the same bits on any rank count: exact partial sums, reduced by a tree.

A float sum depends on the order of its additions, and the order in which ranks hold a sum's terms
depends on the rank count.  Here each rank turns each row of its terms into an exact representation of
their sum, in a compiled kernel: the terms' bits go into a fixed-point accumulator of 32-bit digits that
spans every double (integer additions, exact, about as fast as a plain sum), whose digits become a
non-overlapping floating-point expansion (the partials of ``math.fsum``: a few floats of increasing
magnitude whose exact sum is the row's exact sum).  The ranks merge their expansions (Knuth's error-free
two-sum, no rounding anywhere) with mpi4py's reduction of Python objects, which goes through a binomial
tree (``PyMPI_reduce_p2p``, under mpi4py's default ``rc.fast_reduce``): a rank receives at most
ceil(log2 P) messages, each one expansion per row; merging is exact, so associative and commutative, and
the tree's shape cannot change the result.  Every rank that asks rounds the total once, to the nearest
float (ties to even): the correctly rounded sum, which is also what ``math.fsum`` of all the terms gives,
so the bits are those of one rank's sum in any order.

A row's expansion has as many floats as its exact sum's bits need (one to three for physical sums, at
most about 40): the messages grow with the rows, never with the rank count.  Non-finite terms are summed
apart (in IEEE arithmetic: inf + finite = inf, inf - inf = NaN) and replace the row's result.  Partial
sums may overflow; a total beyond the largest double is not handled.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

# Floats a non-overlapping expansion of doubles can hold: each covers bits of its own among the 2098
# exponent positions of a double.
_SCRATCH = 2200
# A row of non-finite terms: its length is SPECIAL and its single float the IEEE sum of those terms.
SPECIAL = -1


@njit(cache=True, _nrt=False)
def _grow(p, n, x):
    """Add x to the expansion p[:n] (non-overlapping, increasing magnitude), exactly; return its new length
    (``math.fsum``'s inner loop: two-sum against each partial, keeping the non-zero errors)."""
    i = 0
    for j in range(n):
        y = p[j]
        if abs(x) < abs(y):
            x, y = y, x
        hi = x + y
        lo = y - (hi - x)
        if lo != 0.0:
            p[i] = lo
            i += 1
        x = hi
    if x != 0.0:
        p[i] = x
        i += 1
    return i


# The per-rank sum of a row: a fixed-point accumulator of 32-bit digits in int64 words, wide enough for
# every double (2^-1074 to 2^1024, and 2^29 additions more), so that adding a term is a few integer
# operations on its bits, exact, with no loop over partials (``_grow`` costs about 20 times more per
# term).  A finite double is a 2^(e - 1075), a its 53-bit integer mantissa and e its biased exponent (1
# for a subnormal): its bits start at position e - 1 of the accumulator, whose unit is 2^-1074.
_UNIT = -1074
_WORDS = 72
_MASK = (1 << 32) - 1
_BATCH = 1 << 29                # additions a word takes before its carries must be moved up


@njit(cache=True, _nrt=False)
def _deposit(acc, b):
    """acc += the finite double whose bits are ``b``, exactly: its mantissa shifted into three 32-bit words;
    returns the first of them."""
    e = (b >> 52) & 0x7FF
    a = b & 0xFFFFFFFFFFFFF
    if e:
        a |= 0x10000000000000
    else:
        e = 1                                        # a subnormal: no implicit bit, the least exponent
    p = e - 1
    i = p >> 5
    s = p & 31
    lo = (a & _MASK) << s                            # < 2^63
    hi = (a >> 32) << s                              # < 2^52
    c0 = lo & _MASK
    c1 = (lo >> 32) + (hi & _MASK)
    c2 = hi >> 32
    if b < 0:
        c0, c1, c2 = -c0, -c1, -c2
    acc[i] += c0
    acc[i + 1] += c1
    acc[i + 2] += c2
    return i


@njit(cache=True, _nrt=False)
def _carry(acc, i0, i1):
    """Move the carries of words i0 .. i1-1 up, so that each holds a digit in [0, 2^32); word i1 takes the
    rest, with its sign."""
    for i in range(i0, i1):
        c = acc[i] >> 32                                 # floor: a negative word borrows from the next
        acc[i] -= c << 32
        acc[i + 1] += c


@njit(cache=True, _nrt=False)
def _emit(scratch, n, special, flat, used, lengths, r):
    """Row r's expansion (its n parts in ``scratch``, or one special value) appended to ``flat`` at ``used``:
    the new end, or -1 when ``flat`` has no room (the caller grows it and starts again)."""
    if used + n > flat.shape[0]:
        return -1
    for i in range(n):
        flat[used + i] = scratch[i]
    lengths[r] = SPECIAL if special else n
    return used + n


@njit(cache=True, _nrt=False)
def _expand(values, bits, lengths, flat, scratch, acc):
    """Each row of ``values`` [rows, n] (``bits``: the same memory as int64) as an expansion: ``lengths``
    [rows] and the floats one row after the other in ``flat``; returns the floats used, or -1 when ``flat``
    is too short (call again, larger)."""
    used = 0
    for r in range(values.shape[0]):
        special = 0.0
        bad = False
        lo_w, hi_w, count = _WORDS, 0, 0
        for j in range(values.shape[1]):
            b = bits[r, j]
            if (b >> 52) & 0x7FF == 0x7FF:               # inf or NaN
                special += values[r, j]
                bad = True
            elif b & 0x7FFFFFFFFFFFFFFF:                 # not a zero
                i = _deposit(acc, b)
                lo_w, hi_w = min(lo_w, i), max(hi_w, i + 2)
                count += 1
                if count == _BATCH:
                    _carry(acc, lo_w, _WORDS - 1)
                    hi_w, count = _WORDS - 1, 0
        n = 0
        if lo_w < _WORDS:
            top = min(hi_w + 1, _WORDS - 1)
            _carry(acc, lo_w, top)
            sign = 1.0
            if acc[top] < 0:                         # a negative sum: digits of its magnitude, so that no
                sign = -1.0                          # digit exceeds the sum (a borrow could overflow)
                for i in range(lo_w, top + 1):
                    acc[i] = -acc[i]
                _carry(acc, lo_w, top)
            for i in range(lo_w, top + 1):           # digits upward: non-overlapping, increasing
                if acc[i] != 0:
                    n = _grow(scratch, n, sign * math.ldexp(float(acc[i]), 32 * i + _UNIT))
                acc[i] = 0
        if bad:
            n = 1
            scratch[0] = special
        used = _emit(scratch, n, bad, flat, used, lengths, r)
        if used < 0:
            return -1
    return used


@njit(cache=True, _nrt=False)
def _merge(la, fa, lb, fb, lengths, flat, scratch):
    """The row-wise exact sum of two sets of expansions (a and b, as ``_expand`` lays them out) into
    ``lengths``/``flat``; returns the floats used, or -1 when ``flat`` is too short."""
    ia = ib = used = 0
    for r in range(la.shape[0]):
        na = 1 if la[r] == SPECIAL else la[r]
        nb = 1 if lb[r] == SPECIAL else lb[r]
        if la[r] == SPECIAL or lb[r] == SPECIAL:
            # A non-finite sum absorbs every finite term: only the non-finite parts count.
            s = (fa[ia] if la[r] == SPECIAL else 0.0) + (fb[ib] if lb[r] == SPECIAL else 0.0)
            n = 1
            scratch[0] = s
            special = True
        else:
            n = 0
            for i in range(na):
                scratch[n] = fa[ia + i]
                n += 1
            for i in range(nb):
                n = _grow(scratch, n, fb[ib + i])
            special = False
        ia += na
        ib += nb
        used = _emit(scratch, n, special, flat, used, lengths, r)
        if used < 0:
            return -1
    return used


@njit(cache=True, _nrt=False)
def _rounded(p, n):
    """The expansion p[:n] rounded once to the nearest float, ties to even (``math.fsum``'s last step: add
    from the top until a sum is inexact, then correct a half-way case by the sign of what lies below)."""
    if n == 0:
        return 0.0
    n -= 1
    hi = p[n]
    lo = 0.0
    while n > 0:
        x = hi
        n -= 1
        y = p[n]
        hi = x + y
        lo = y - (hi - x)
        if lo != 0.0:
            break
    if n > 0 and ((lo < 0.0 and p[n - 1] < 0.0) or (lo > 0.0 and p[n - 1] > 0.0)):
        y = lo * 2.0
        x = hi + y
        if y == x - hi:
            hi = x
    return hi


@njit(cache=True, _nrt=False)
def _round_all(lengths, flat, out, rest, scratch):
    """out[r]: each row rounded once; with ``rest`` (one element per row, or empty): also what the rounding
    left, itself rounded once (the exact sum less out[r])."""
    i = 0
    for r in range(lengths.shape[0]):
        if lengths[r] == SPECIAL:
            out[r] = flat[i]
            if rest.shape[0]:
                rest[r] = np.nan
            i += 1
            continue
        n = lengths[r]
        out[r] = _rounded(flat[i:i + n], n)
        if rest.shape[0]:
            for j in range(n):
                scratch[j] = flat[i + j]
            m = _grow(scratch, n, -out[r])
            rest[r] = _rounded(scratch, m)
        i += n
    return 0


class Expansions:
    """Rows of exact sums, each a non-overlapping expansion: ``lengths`` [rows] (SPECIAL for a non-finite
    sum) and the floats of every row one after the other in ``flat``.  What travels between ranks."""

    __slots__ = ("lengths", "flat")

    def __init__(self, lengths: np.ndarray, flat: np.ndarray):
        self.lengths, self.flat = lengths, flat

    def __reduce__(self):
        return Expansions, (self.lengths, self.flat)

    @classmethod
    def of(cls, values: np.ndarray) -> "Expansions":
        """The exact sum of each row of ``values`` [rows, n] (float64)."""
        v = np.ascontiguousarray(values, np.float64)
        lengths = np.zeros(v.shape[0], np.int32)
        room = max(2 * v.shape[0], 8)
        while True:
            flat = np.empty(room, np.float64)
            used = _expand(v, v.view(np.int64), lengths, flat, np.empty(_SCRATCH), np.zeros(_WORDS, np.int64))
            if used >= 0:
                return cls(lengths, flat[:used].copy())
            room *= 4

    def __add__(self, other: "Expansions") -> "Expansions":
        """The row-wise exact sum (associative and commutative: the reduction's operator)."""
        lengths = np.zeros(len(self.lengths), np.int32)
        room = len(self.flat) + len(other.flat) + 8
        while True:
            flat = np.empty(room, np.float64)
            used = _merge(self.lengths, self.flat, other.lengths, other.flat, lengths, flat, np.empty(_SCRATCH))
            if used >= 0:
                return Expansions(lengths, flat[:used].copy())
            room *= 4

    def rounded(self, remainder: bool = False):
        """Each row's exact sum rounded once (the correctly rounded sum); with ``remainder`` also (sums,
        rests), rest the exact sum less the rounded one, rounded once (NaN for a non-finite row)."""
        out = np.empty(len(self.lengths))
        rest = np.empty(len(self.lengths) if remainder else 0)
        _round_all(self.lengths, self.flat, out, rest, np.empty(_SCRATCH))
        return (out, rest) if remainder else out


def _add(a, b):
    return a + b


def warm() -> None:
    """Run every compiled kernel of the exact sums once on a tiny sum (``engine.compile``: they are compiled
    with the time loop, by one rank per kernel cache, instead of by every rank at its first flush)."""
    e = Expansions.of(np.zeros((1, 2)))
    (e + e).rounded(remainder=True)


def exact_sums(comm, blocks: list, root: int | None = None, remainder: bool = False):
    """The correctly rounded sums, over every rank of ``comm`` and the last axis, of each array of
    ``blocks`` (shapes [..., n_i], the leading shape the same on every rank, n_i this rank's own): a list
    of arrays of the leading shapes, the same bits on any rank count.  With ``root`` only that rank gets
    them (None elsewhere; a reduce instead of an allreduce); with ``remainder`` each item is a pair
    (sums, what the rounding left, rounded once).  Collective; ``comm`` None or of one rank: no MPI."""
    shapes = [np.shape(b)[:-1] for b in blocks]
    rows = [int(np.prod(s)) for s in shapes]
    mine = None
    for b, r in zip(blocks, rows):
        e = Expansions.of(np.reshape(b, (r, np.shape(b)[-1])))
        mine = e if mine is None else Expansions(np.concatenate([mine.lengths, e.lengths]),
                                                 np.concatenate([mine.flat, e.flat]))
    if comm is not None and comm.Get_size() > 1:
        mine = comm.allreduce(mine, op=_add) if root is None else comm.reduce(mine, op=_add, root=root)
        if mine is None:
            return None
    got = mine.rounded(remainder)
    cut = np.cumsum([0] + rows)
    if remainder:
        return [(got[0][a:b].reshape(s), got[1][a:b].reshape(s)) for a, b, s in zip(cut, cut[1:], shapes)]
    return [got[a:b].reshape(s) for a, b, s in zip(cut, cut[1:], shapes)]
