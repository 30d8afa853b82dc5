"""The bulk Born update of one row segment: bond forces fused with damped Verlet.

Responsible for the arithmetic of a node update only; which rows and columns
to update comes from the row schedule (``parallel.layout``).

Each block is stored as 2D arrays [row, column] of the displacements from
the reference lattice, x and y apart, at two Verlet levels.  A step reads
level ``c`` (u(t)) and overwrites level ``p`` (u(t - dt)) with u(t + dt):

    u(t+dt) = (2 u(t) - (1 - zeta dt/2) u(t-dt) + dt^2 F(t)) / (1 + zeta dt/2)

(``keep`` = 1 - zeta dt/2, ``inv`` = 1/(1 + zeta dt/2); with zeta = 0 the
damping terms are skipped, which gives the same bits).  F is the Born force
(paper Eq. 2.1) written with the 2x2 stiffness of each bond direction,

    F_i = sum_j K_j (u_j - u_i),   K_j = (k_n - k_t) n_j n_j^T + k_t I,

where opposite bonds share K: K_R = K_L = [[k_n, 0], [0, k_t]] and, with
A = (k_n - k_t)/4 + k_t, B = sqrt(3)(k_n - k_t)/4, C = 3(k_n - k_t)/4 + k_t,
K_UR = K_DL = [[A, B], [B, C]], K_UL = K_DR = [[A, -B], [-B, C]].  For an
interior node the pairs fold into

    F_x = k_n (u_L + u_R - 2u)_x + A (sum of the 4 diagonal - 4u)_x + B (UR + DL - UL - DR)_y
    F_y = k_t (u_L + u_R - 2u)_y + B (UR + DL - UL - DR)_x + C (sum of the 4 diagonal - 4u)_y

Row r's up and down neighbours of column c are at columns c - 1 + s and
c + s, with s = 0 or 1 by the row's x offset.  ``K`` holds [k_n, k_t, A, B, C]
of each block (row ``blk``), in the state's float type; no float literal enters a loop
(2u is u + u), so float32 stays float32.

Loops index 1D views from 0 (``for k in range(n)``): indices a compiler can
prove non-negative, so the loop vectorises.  A node sums its terms in the
same order whichever rank or task computes it, so results do not depend on
the decomposition.
"""
from numba import njit

from .floats import like

# Bits of the neighbour mask: right, up-right, up-left, left, down-left, down-right.
R_, UR_, UL_, L_, DL_, DR_ = 1, 2, 4, 8, 16, 32


@njit(cache=True, inline="always")
def _verlet(u, old, f, dt2, keep, inv, damped):
    if damped:
        return ((u + u) - keep * old + dt2 * f) * inv
    return (u + u) - old + dt2 * f


@njit(cache=True, error_model="numpy", _nrt=False)
def row_full(cx, cy, px, py, r, j0, n, s, K, blk, dt2, keep, inv, damped):
    """Interior row segment: all six bonds, no external force.  Writes u(t+dt) into px, py."""
    kn, kt, a, b, c = K[blk, 0], K[blk, 1], K[blk, 2], K[blk, 3], K[blk, 4]
    xm, x0, xp = cx[r, j0 - 1:j0 - 1 + n], cx[r, j0:j0 + n], cx[r, j0 + 1:j0 + 1 + n]
    ym, y0, yp = cy[r, j0 - 1:j0 - 1 + n], cy[r, j0:j0 + n], cy[r, j0 + 1:j0 + 1 + n]
    xul, xur = cx[r + 1, j0 - 1 + s:j0 - 1 + s + n], cx[r + 1, j0 + s:j0 + s + n]
    yul, yur = cy[r + 1, j0 - 1 + s:j0 - 1 + s + n], cy[r + 1, j0 + s:j0 + s + n]
    xdl, xdr = cx[r - 1, j0 - 1 + s:j0 - 1 + s + n], cx[r - 1, j0 + s:j0 + s + n]
    ydl, ydr = cy[r - 1, j0 - 1 + s:j0 - 1 + s + n], cy[r - 1, j0 + s:j0 + s + n]
    ox, oy = px[r, j0:j0 + n], py[r, j0:j0 + n]
    for k in range(n):
        ux, uy = x0[k], y0[k]
        ux2, uy2 = ux + ux, uy + uy
        hx = (xm[k] + xp[k]) - ux2
        hy = (ym[k] + yp[k]) - uy2
        pxs, qxs = xur[k] + xdl[k], xul[k] + xdr[k]
        pys, qys = yur[k] + ydl[k], yul[k] + ydr[k]
        fx = kn * hx + a * ((pxs + qxs) - (ux2 + ux2)) + b * (pys - qys)
        fy = kt * hy + b * (pxs - qxs) + c * ((pys + qys) - (uy2 + uy2))
        ox[k] = _verlet(ux, ox[k], fx, dt2, keep, inv, damped)
        oy[k] = _verlet(uy, oy[k], fy, dt2, keep, inv, damped)


@njit(cache=True, error_model="numpy", _nrt=False)
def row_edge(cx, cy, px, py, r, j0, n, s, K, blk, dt2, keep, inv, damped, up, ex, ey, gx, gy):
    """Row segment of a block's top row (``up`` False: no up bonds) or bottom row (``up`` True: no down bonds).

    Adds the per-column external force (ex, ey), e.g. interface bonds, and
    the uniform force (gx, gy), e.g. the normal load, after the bond forces.
    """
    kn, kt, a, b, c = K[blk, 0], K[blk, 1], K[blk, 2], K[blk, 3], K[blk, 4]
    rr = r + 1 if up else r - 1
    xm, x0, xp = cx[r, j0 - 1:j0 - 1 + n], cx[r, j0:j0 + n], cx[r, j0 + 1:j0 + 1 + n]
    ym, y0, yp = cy[r, j0 - 1:j0 - 1 + n], cy[r, j0:j0 + n], cy[r, j0 + 1:j0 + 1 + n]
    # The diagonal neighbour at c - 1 + s and the one at c + s.  Up: UL (K_UL) and UR (K_UR);
    # down: DL (K_UR) and DR (K_UL).  ``p`` is the one along K_UR, ``q`` along K_UL.
    xa, xb = cx[rr, j0 - 1 + s:j0 - 1 + s + n], cx[rr, j0 + s:j0 + s + n]
    ya, yb = cy[rr, j0 - 1 + s:j0 - 1 + s + n], cy[rr, j0 + s:j0 + s + n]
    exs, eys = ex[j0:j0 + n], ey[j0:j0 + n]
    ox, oy = px[r, j0:j0 + n], py[r, j0:j0 + n]
    if up:
        xp_, xq_, yp_, yq_ = xb, xa, yb, ya
    else:
        xp_, xq_, yp_, yq_ = xa, xb, ya, yb
    for k in range(n):
        ux, uy = x0[k], y0[k]
        hx = (xm[k] + xp[k]) - (ux + ux)
        hy = (ym[k] + yp[k]) - (uy + uy)
        dpx, dpy = xp_[k] - ux, yp_[k] - uy
        dqx, dqy = xq_[k] - ux, yq_[k] - uy
        fx = kn * hx + a * (dpx + dqx) + b * (dpy - dqy) + exs[k] + gx
        fy = kt * hy + b * (dpx - dqx) + c * (dpy + dqy) + eys[k] + gy
        ox[k] = _verlet(ux, ox[k], fx, dt2, keep, inv, damped)
        oy[k] = _verlet(uy, oy[k], fy, dt2, keep, inv, damped)


@njit(cache=True, error_model="numpy", _nrt=False)
def node_masked(cx, cy, px, py, r, j, s, K, blk, dt2, keep, inv, damped, mask, fx, fy):
    """One node with only the bonds in ``mask`` (block edges), plus the external force (fx, fy).

    Without branches: a missing neighbour is read from the zero ghost cells
    around the block (or a real cell) and its term weighed by 0.
    """
    kn, kt, a, b, c = K[blk, 0], K[blk, 1], K[blk, 2], K[blk, 3], K[blk, 4]
    ux, uy = cx[r, j], cy[r, j]
    wr, wur, wul = like(mask & R_, ux), like((mask & UR_) >> 1, ux), like((mask & UL_) >> 2, ux)
    wl, wdl, wdr = like((mask & L_) >> 3, ux), like((mask & DL_) >> 4, ux), like((mask & DR_) >> 5, ux)
    hx = wr * (cx[r, j + 1] - ux) + wl * (cx[r, j - 1] - ux)
    hy = wr * (cy[r, j + 1] - uy) + wl * (cy[r, j - 1] - uy)
    # Along K_UR: up-right and down-left; along K_UL: up-left and down-right.
    dpx = wur * (cx[r + 1, j + s] - ux) + wdl * (cx[r - 1, j - 1 + s] - ux)
    dpy = wur * (cy[r + 1, j + s] - uy) + wdl * (cy[r - 1, j - 1 + s] - uy)
    dqx = wul * (cx[r + 1, j - 1 + s] - ux) + wdr * (cx[r - 1, j + s] - ux)
    dqy = wul * (cy[r + 1, j - 1 + s] - uy) + wdr * (cy[r - 1, j + s] - uy)
    gx = kn * hx + a * (dpx + dqx) + b * (dpy - dqy) + fx
    gy = kt * hy + b * (dpx - dqx) + c * (dpy + dqy) + fy
    px[r, j] = _verlet(ux, px[r, j], gx, dt2, keep, inv, damped)
    py[r, j] = _verlet(uy, py[r, j], gy, dt2, keep, inv, damped)
