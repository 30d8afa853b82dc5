"""Global sums that give the same bits on any rank count (``parallel.exact_sum``), against exact rational
arithmetic (``fractions.Fraction``) and ``math.fsum``: each rank's share summed exactly, the shares merged
in any order or tree, the total rounded once to the nearest float."""
import math
from fractions import Fraction

import numpy as np
import pytest

from parslip.parallel.exact_sum import Expansions, exact_sums


def _rows(rng, count):
    """Rows that make plain sums go wrong: cancellation, magnitudes from 1e-300 to 1e300, subnormals,
    half-way cases, and plain normal numbers."""
    rows = []
    for _ in range(count):
        n = int(rng.integers(1, 14))
        kind = int(rng.integers(0, 6))
        if kind == 0:
            v = rng.standard_normal(n)
        elif kind == 1:
            v = rng.standard_normal(n) * 10.0 ** rng.integers(-300, 300, n)
        elif kind == 2:
            x = rng.standard_normal(n) * 1e16
            v = np.concatenate([x, -x, rng.standard_normal(2)])
        elif kind == 3:
            v = np.array([1.0, 2.0 ** -53, 2.0 ** -106, -2.0 ** -160, 5e-324, -3 * 5e-324])[:n]
        elif kind == 4:
            v = np.array([1e16, 1.0, 1e-16, -1e16, 2.0 ** -1073])[:n]
        else:
            v = rng.standard_normal(n) * 2.0 ** rng.integers(-1074, -1000, n)      # subnormal and tiny
        rows.append(rng.permutation(v))
    return rows


def _nearest(exact: Fraction) -> float:
    """The float nearest to a rational, ties to even (Python's own rounding of a Fraction)."""
    return float(exact)


def test_a_rows_sum_split_over_ranks_is_the_correctly_rounded_sum_in_any_merge_order():
    rng = np.random.default_rng(7)
    for v in _rows(rng, 4000):
        exact = sum((Fraction(x) for x in v), Fraction(0))
        k = int(rng.integers(1, 6))                        # "ranks", each with a share of the terms
        shares = [Expansions.of(p[None, :]) for p in np.array_split(v, k)]
        rng.shuffle(shares)
        while len(shares) > 1:                             # merged as a random tree
            i = int(rng.integers(0, len(shares) - 1))
            shares[i:i + 2] = [shares[i] + shares[i + 1]]
        got, rest = shares[0].rounded(remainder=True)
        assert got[0] == _nearest(exact) == math.fsum(v), v.tolist()
        assert rest[0] == _nearest(exact - Fraction(got[0])), v.tolist()


def test_the_sum_is_not_the_ordered_sum_where_that_one_rounds_twice():
    """((1e16 + 1) + 1) - 1e16 is 0 in order: each 1 is lost; the exact sum is 2."""
    v = np.array([[1e16, 1.0, 1.0, -1e16]])
    ordered = ((v[0, 0] + v[0, 1]) + v[0, 2]) + v[0, 3]
    assert ordered == 0.0 and exact_sums(None, [v])[0][0] == 2.0


def test_non_finite_terms_give_the_ieee_sum_of_them():
    v = np.array([[1.0, np.inf, 2.0], [np.nan, 1.0, 2.0], [np.inf, -np.inf, 0.0], [-np.inf, 1e308, 1e308]])
    got = exact_sums(None, [v])[0]
    assert got[0] == np.inf and np.isnan(got[1]) and np.isnan(got[2]) and got[3] == -np.inf
    # Partial sums beyond the largest double do not matter when the total is a double.
    assert exact_sums(None, [np.array([[1e308, 1e308, -1e308]])])[0][0] == 1e308
    # Merged with a finite share, a non-finite share stays what it was.
    a, b = Expansions.of(np.array([[np.inf], [1.0]])), Expansions.of(np.array([[5.0], [np.nan]]))
    got = (a + b).rounded()
    assert got[0] == np.inf and np.isnan(got[1])


def test_blocks_keep_their_shapes_and_an_empty_share_counts_nothing():
    rng = np.random.default_rng(3)
    a, b = rng.standard_normal((4, 3, 5)), rng.standard_normal((2, 0))
    got = exact_sums(None, [a, b])
    assert got[0].shape == (4, 3) and got[1].shape == (2,)
    assert np.array_equal(got[0], np.vectorize(lambda i, j: math.fsum(a[i, j]))(*np.indices((4, 3))))
    assert np.array_equal(got[1], np.zeros(2))


def test_a_share_travels_as_a_few_floats_per_row():
    """What each rank sends: one expansion per row, a few floats (physical sums: one to three), however many
    terms the row had."""
    rng = np.random.default_rng(11)
    e = Expansions.of(rng.standard_normal((1000, 5000)))
    assert e.lengths.max() <= 4 and len(e.flat) == e.lengths.sum()


def test_mpi4py_reduces_python_objects_through_a_tree():
    """The reduction relies on mpi4py's tree (no rank gathers every share): its default must hold."""
    import mpi4py
    assert mpi4py.rc.fast_reduce


@pytest.mark.parallel(nprocs=2)
def test_two_ranks_give_the_bits_of_one():
    from mpi4py import MPI
    comm = MPI.COMM_WORLD
    rng = np.random.default_rng(5)
    terms = rng.standard_normal((50, 14)) * 10.0 ** rng.integers(-20, 20, (50, 14))
    mine = terms[:, comm.Get_rank()::2]
    want = np.array([math.fsum(row) for row in terms])
    got = exact_sums(comm, [mine])[0]
    assert np.array_equal(got, want)
    at_root = exact_sums(comm, [mine], root=0)
    assert (at_root is None) == (comm.Get_rank() != 0)
    if at_root is not None:
        assert np.array_equal(at_root[0], want)
