"""Quantities computed only when asked (snapshots, tests): node stress and bond energy.

Work on the block arrays of ``engine.state`` for a list of OWNED nodes given
as (block, array row, array column).  Neighbour k of node (r, c) sits at
(r + dr_k, c + dc_k) with s = 0 or 1 by the row's x offset:

    k:     0 right   1 up-right   2 up-left    3 left    4 down-left   5 down-right
    dr,dc: (0, 1)    (1, s)       (1, s - 1)   (0, -1)   (-1, s - 1)   (-1, s)

and exists when it lies inside the block.  A bond's force on node i is
f = (k_n - k_t) [(u_j - u_i).n] n + k_t (u_j - u_i) (paper Eq. 2.1).
"""
import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def _nbr(k, r, c, s):
    if k == 0:
        return r, c + 1
    if k == 1:
        return r + 1, c + s
    if k == 2:
        return r + 1, c + s - 1
    if k == 3:
        return r, c - 1
    if k == 4:
        return r - 1, c + s - 1
    return r - 1, c + s


@njit(cache=True, forceinline=True)
def _bond_diffs(bx, by, tx, ty, geo, b, r, c, kmax, d):
    """u_j - u_i (float64) of node (b, r, c)'s bonds 0..kmax-1 into d[k], and whether each bond exists."""
    if b == 0:
        ax, ay = bx, by
    else:
        ax, ay = tx, ty
    rlo, rhi, jlo, jhi, par = geo[b, 0], geo[b, 1], geo[b, 2], geo[b, 3], geo[b, 4]
    s = (r - rlo + par) % 2
    for k in range(kmax):
        rr, cc = _nbr(k, r, c, s)
        if rr < rlo or rr >= rhi or cc < jlo or cc >= jhi:
            d[k, 2] = 0.0
            continue
        d[k, 0] = float(ax[rr, cc]) - float(ax[r, c])
        d[k, 1] = float(ay[rr, cc]) - float(ay[r, c])
        d[k, 2] = 1.0


@njit(cache=True)
def node_stress(bx, by, tx, ty, blk, row, col, geo, kk, dirs, scale, out):
    """Virial stress of each listed node, sigma_ab = sum_j f_a n_b a / (2 Omega), times ``scale``.

    ``geo[b]`` = [first, end array row, first, end array column, parity] of block b's nodes; ``kk[b]`` = [k_n, k_t].
    ``scale`` = 1/(2 Omega rho c_r^2) = 1/(2 c_r^2) gives rho c_r^2.  out[:, 0..2] = sxx, syy, sxy,
    where sxy = sum f_x n_y is the x-traction on horizontal planes (the Born stress is not symmetric).
    """
    d = np.zeros((6, 3))
    for m in range(blk.shape[0]):
        b = blk[m]
        _bond_diffs(bx, by, tx, ty, geo, b, row[m], col[m], 6, d)
        kn, kt = kk[b, 0], kk[b, 1]
        sxx = 0.0
        syy = 0.0
        sxy = 0.0
        for k in range(6):
            if d[k, 2] == 0.0:
                continue
            nx, ny = dirs[k, 0], dirs[k, 1]
            p = (kn - kt) * (d[k, 0] * nx + d[k, 1] * ny)
            fx = p * nx + kt * d[k, 0]
            fy = p * ny + kt * d[k, 1]
            sxx += fx * nx
            syy += fy * ny
            sxy += fx * ny
        out[m, 0] = sxx * scale
        out[m, 1] = syy * scale
        out[m, 2] = sxy * scale


@njit(cache=True)
def bond_energy(bx, by, tx, ty, blk, row, col, geo, kk, dirs, out):
    """Energy of each listed node's bonds 0..2 (each bulk bond counted once), in m c^2:
    1/2 [k_n (du.n)^2 + k_t (|du|^2 - (du.n)^2)]."""
    d = np.zeros((3, 3))
    for m in range(blk.shape[0]):
        b = blk[m]
        _bond_diffs(bx, by, tx, ty, geo, b, row[m], col[m], 3, d)
        kn, kt = kk[b, 0], kk[b, 1]
        e = 0.0
        for k in range(3):
            if d[k, 2] == 0.0:
                continue
            dx, dy = d[k, 0], d[k, 1]
            dn = dx * dirs[k, 0] + dy * dirs[k, 1]
            e += 0.5 * (kn * dn * dn + kt * (dx * dx + dy * dy - dn * dn))
        out[m] = e
