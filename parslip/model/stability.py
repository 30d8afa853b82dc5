"""The stability limit of the time step: dt < 2/omega_max.

Responsible for omega_max, the highest eigenfrequency of the whole lattice
(both blocks, the interface springs, the fixed row), from the assembled
sparse stiffness matrix (m = 1, so omega^2 are its eigenvalues).  The
damped Verlet update of ``kernels.verlet_update`` is stable for
omega dt <= 2 whatever zeta is (its characteristic polynomial has the root
-1 exactly at omega dt = 2), so dt_max = 2/omega_max.  The paper's rule
dt < a/c_l is far too loose for the stiff substrate.

Breaking bonds and prescribing driven x-coordinates only remove stiffness
or degrees of freedom, which cannot raise omega_max (Cauchy interlacing).

The same bits on any host: the solvers behind omega_max are not portable in
their last bits (ARPACK's and LAPACK's vector kernels are chosen per CPU by
OpenBLAS: push's Lanczos value is 24.45511710235529 with the default kernel on
an AVX-512 host and 24.45511710235539 with the Haswell kernel, 4e-15 apart).
So omega_max is rounded UP to OMEGA_BITS = 24 significant bits
(``round_up``: 6e-8 relative, far coarser than the solvers' 1e-9 tolerance and
the 1e-14 host-to-host spread, and upward, so 2/omega_max stays a safe
limit).  Every host then gets the same omega_max, unless the exact value lies
within that spread of a 24-bit boundary (a chance of about 1e-7 per scene,
which ``tests/test_portable.py`` would catch on the shipped scenes).  The
bound's ``bulk_omega2`` uses only Python's scalar arithmetic and libm's cos,
no vector or LAPACK code.
"""
from __future__ import annotations

import math

import numpy as np

from .lattice import BOTTOM, DIRECTIONS, DRIVEN, FIXED, Lattice


def stiffness_matrix(lattice: Lattice, kn, kt, kx: float, ky: float, mode: str = "none", spring: float = 0.0,
                     drive_rows=None):
    """K (2N x 2N, DOF order x0, y0, x1, ...) and the mask of free DOFs; with ``spring`` > 0 each driven
    node of ``mode`` (and ``drive_rows``) is tied in x to a fixed point by a spring of that stiffness."""
    import scipy.sparse as sp
    nodes = lattice.nodes_in_columns(0, lattice.ncols)
    nbr = lattice.neighbour_gids(nodes)
    rows, cols, vals = [], [], []

    def add(i, j, kxx, kxy, kyy):
        for (a, b, v) in ((0, 0, kxx), (0, 1, kxy), (1, 0, kxy), (1, 1, kyy)):
            rows.extend([2 * i + a, 2 * j + b, 2 * i + a, 2 * j + b])
            cols.extend([2 * i + b, 2 * j + a, 2 * j + b, 2 * i + a])
            vals.extend([v, v, -v, -v])

    for k in range(3):          # each bulk bond once
        j = nbr[:, k]
        m = j >= 0
        i = nodes["gid"][m]
        j = j[m]
        b = nodes["block"][m]
        knb, ktb = np.asarray(kn)[b], np.asarray(kt)[b]
        nx, ny = DIRECTIONS[k]
        kxx = (knb - ktb) * nx * nx + ktb
        kxy = (knb - ktb) * nx * ny
        kyy = (knb - ktb) * ny * ny + ktb
        for (a, c, v) in ((0, 0, kxx), (0, 1, kxy), (1, 0, kxy), (1, 1, kyy)):
            rows.append(np.concatenate([2 * i + a, 2 * j + a, 2 * i + a, 2 * j + a]))
            cols.append(np.concatenate([2 * i + c, 2 * j + c, 2 * j + c, 2 * i + c]))
            vals.append(np.concatenate([v, v, -v, -v]))
    if lattice.has_interface and lattice.rigid:
        # Springs to fixed sites: only their diagonal terms on the block's interface nodes.
        it = lattice.gid(1, 0, lattice.top.col0 + np.arange(lattice.n_top_sites))
        for (a, kk) in ((0, kx), (1, ky)):
            rows.append(2 * it + a)
            cols.append(2 * it + a)
            vals.append(np.full(len(it), kk))
    elif lattice.has_interface:
        s = np.arange(lattice.n_top_sites)
        t = lattice.top
        it = lattice.gid(1, 0, t.col0 + s)
        ib = lattice.gid(BOTTOM, lattice.bottom.rows - 1, t.col0 + s)
        for (a, kk) in ((0, kx), (1, ky)):
            v = np.full(len(s), kk)
            rows.append(np.concatenate([2 * it + a, 2 * ib + a, 2 * it + a, 2 * ib + a]))
            cols.append(np.concatenate([2 * it + a, 2 * ib + a, 2 * ib + a, 2 * it + a]))
            vals.append(np.concatenate([v, v, -v, -v]))
    if spring > 0:
        driven = nodes["gid"][lattice.kinds(nodes, mode, drive_rows) == DRIVEN]
        rows.append(2 * driven)
        cols.append(2 * driven)
        vals.append(np.full(len(driven), float(spring)))
    n = 2 * lattice.n_nodes
    K = sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(n, n)).tocsr()
    free = np.ones(n, bool)
    fixed = lattice.kinds(nodes, mode) == FIXED
    free[2 * nodes["gid"][fixed]] = False
    free[2 * nodes["gid"][fixed] + 1] = False
    return K, free


LANCZOS_MAX_DOFS = 60_000
OMEGA_BITS = 24         # significant bits omega_max is rounded up to (module docstring)


def round_up(x: float, bits: int = OMEGA_BITS) -> float:
    """x > 0 rounded up to ``bits`` significant bits: the smallest m 2^e >= x with m < 2^bits an integer.
    Exact (frexp, ceil and ldexp only), so the same on every host."""
    m, e = math.frexp(x)                  # x = m 2^e, 1/2 <= m < 1
    return math.ldexp(math.ceil(math.ldexp(m, bits)), e - bits)


def bulk_omega2(kn: float, kt: float) -> float:
    """max over the Brillouin zone of omega^2(k) for an infinite Born lattice.

    D(k) = sum_j (1 - cos k.a_j) [(k_n - k_t) n_j n_j^T + k_t I] (six neighbours j); a grid
    search, then a local refinement of its best point (Nelder-Mead).  Portable: D's largest eigenvalue
    in closed form, (a + c)/2 + sqrt(((a - c)/2)^2 + b^2) for D = [[a, b], [b, c]], in Python's scalar
    arithmetic in a fixed order, and math.cos (libm) rather than NumPy's vector cos or LAPACK, whose
    last bits depend on the CPU's vector units.
    """
    from scipy.optimize import minimize

    d = kn - kt
    mats = [(nx, ny, d * nx * nx + kt, d * nx * ny, d * ny * ny + kt) for nx, ny in DIRECTIONS.tolist()]

    def lam(k):
        kx, ky = float(k[0]), float(k[1])
        a = b = c = 0.0
        for nx, ny, kxx, kxy, kyy in mats:
            w = 1.0 - math.cos(kx * nx + ky * ny)
            a, b, c = a + w * kxx, b + w * kxy, c + w * kyy
        h = 0.5 * (a - c)
        return 0.5 * (a + c) + math.sqrt(h * h + b * b)

    g = np.linspace(-2 * np.pi, 2 * np.pi, 121)
    best = max(((lam((a, b)), (a, b)) for a in g for b in g), key=lambda p: p[0])
    res = minimize(lambda k: -lam(k), best[1], method="Nelder-Mead", options={"xatol": 1e-10, "fatol": 1e-13})
    return float(max(best[0], -res.fun))


def omega_max(lattice: Lattice, kn, kt, kx: float, ky: float, spring: float = 0.0, mode: str = "none",
              drive_rows=None) -> tuple[float, str]:
    """Highest eigenfrequency of the lattice with its interface bonds, and how it was found.

    Up to LANCZOS_MAX_DOFS degrees of freedom: the largest eigenvalue of the
    assembled stiffness (Lanczos; dense below 200).  Above: the rigorous
    bound omega^2 <= max over blocks of the infinite-lattice omega^2 + 2 max(k_x, k_y):
    a finite block has fewer bonds than the infinite lattice (smaller
    Rayleigh quotient), and each node has at most one interface bond, whose
    stiffness adds at most 2k.  The bound also covers re-formed bonds that
    pair other nodes; it is within 0.5 % of the exact value for the paper's
    scenes.  A loader spring k_s on the driven nodes adds at most k_s to omega^2 (a diagonal term), in the
    bound as in the assembled stiffness.

    Either value is returned rounded up to OMEGA_BITS significant bits (``round_up``), so that every
    x86-64 host derives the same omega_max, dt and step counts from a scene (module docstring).
    """
    ndof = 2 * lattice.n_nodes
    if ndof > LANCZOS_MAX_DOFS:
        blocks = [b for b in (0, 1) if lattice.blocks[b].rows > 0 and lattice.numbered[b]]
        w2 = max(bulk_omega2(kn[b], kt[b]) for b in blocks)
        if lattice.has_interface:
            w2 += 2 * max(kx, ky)
        return round_up(math.sqrt(w2 + spring)), "bound"
    from scipy.sparse.linalg import eigsh
    K, free = stiffness_matrix(lattice, kn, kt, kx, ky, mode, spring, drive_rows)
    K = K[free][:, free]
    if K.shape[0] <= 200:
        lam = np.linalg.eigvalsh(K.toarray())[-1]
    else:
        lam = eigsh(K, k=1, which="LA", tol=1e-9, return_eigenvectors=False,
                    v0=np.ones(K.shape[0]), maxiter=100000)[0]
    return round_up(math.sqrt(float(lam))), "lanczos"


def dt_max(omega: float) -> float:
    return 2.0 / omega
