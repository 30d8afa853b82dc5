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


@njit(cache=True)
def node_stress(bx, by, tx, ty, blk, row, col, geo, kk, dirs, scale, out):
    """Virial stress of each listed node, sigma_ab = sum_j f_a n_b a / (2 Omega), times ``scale``.

    ``geo[b]`` = [first, end array row, first, end array column, parity] of block b's nodes; ``kk[b]`` = [k_n, k_t].
    ``scale`` = 1/(2 Omega rho c_r^2) = 1/(2 c_r^2) gives rho c_r^2.  out[:, 0..2] = sxx, syy, sxy,
    where sxy = sum f_x n_y is the x-traction on horizontal planes (the Born stress is not symmetric).
    """
    for m in range(blk.shape[0]):
        b, r, c = blk[m], row[m], col[m]
        if b == 0:
            ax, ay = bx, by
        else:
            ax, ay = tx, ty
        rlo, rhi, jlo, jhi, par = geo[b, 0], geo[b, 1], geo[b, 2], geo[b, 3], geo[b, 4]
        s = (r - rlo + par) % 2
        kn, kt = kk[b, 0], kk[b, 1]
        kd = kn - kt
        ux, uy = float(ax[r, c]), float(ay[r, c])
        sxx = 0.0
        syy = 0.0
        sxy = 0.0
        for k in range(6):
            rr, cc = _nbr(k, r, c, s)
            if rr < rlo or rr >= rhi or cc < jlo or cc >= jhi:
                continue
            nx, ny = dirs[k, 0], dirs[k, 1]
            dx = float(ax[rr, cc]) - ux
            dy = float(ay[rr, cc]) - uy
            p = kd * (dx * nx + dy * ny)
            fx = p * nx + kt * dx
            fy = p * ny + kt * dy
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
    for m in range(blk.shape[0]):
        b, r, c = blk[m], row[m], col[m]
        if b == 0:
            ax, ay = bx, by
        else:
            ax, ay = tx, ty
        rlo, rhi, jlo, jhi, par = geo[b, 0], geo[b, 1], geo[b, 2], geo[b, 3], geo[b, 4]
        s = (r - rlo + par) % 2
        kn, kt = kk[b, 0], kk[b, 1]
        e = 0.0
        for k in range(3):
            rr, cc = _nbr(k, r, c, s)
            if rr < rlo or rr >= rhi or cc < jlo or cc >= jhi:
                continue
            dx = float(ax[rr, cc]) - float(ax[r, c])
            dy = float(ay[rr, cc]) - float(ay[r, c])
            dn = dx * dirs[k, 0] + dy * dirs[k, 1]
            e += 0.5 * (kn * dn * dn + kt * (dx * dx + dy * dy - dn * dn))
        out[m] = e
