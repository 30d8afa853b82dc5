"""The bulk Born update of one row segment: bond forces fused with damped Verlet.

Responsible for the arithmetic of a node update only; which rows and columns
to update comes from the row schedule (``parallel.layout``).

Each block is stored as 2D arrays [row, column] of the displacements from
the reference lattice, x and y apart, at two Verlet levels.  A step reads
level ``c`` (u(t)) and overwrites level ``p`` (u(t - dt)) with u(t + dt):

    u(t+dt) = (2 u(t) - (1 - zeta dt/2) u(t-dt) + dt^2 F(t)) / (1 + zeta dt/2)
            = u(t) + B (u(t) - u(t-dt)) + C F(t),
    B = (1 - zeta dt/2)/(1 + zeta dt/2),  C = dt^2/(1 + zeta dt/2),

the second form adding a small increment to u, never forming 2u - u_old;
with zeta = 0, B = 1 and its multiplication is skipped (same bits).  F is the
Born force (paper Eq. 2.1) written with the 2x2 stiffness of each bond
direction,

    F_i = sum_j K_j (u_j - u_i),   K_j = (k_n - k_t) n_j n_j^T + k_t I,

where opposite bonds share K: K_R = K_L = [[k_n, 0], [0, k_t]] and, with
A = (k_n - k_t)/4 + k_t, B' = sqrt(3)(k_n - k_t)/4, C' = 3(k_n - k_t)/4 + k_t,
K_UR = K_DL = [[A, B'], [B', C']], K_UL = K_DR = [[A, -B'], [-B', C']].  With
h = d_L + d_R, P = d_UR + d_DL, Q = d_UL + d_DR (d_j = u_j - u_i, each bond's
difference formed first, so float32 keeps the strain):

    F_x = k_n h_x + A (P_x + Q_x) + B' (P_y - Q_y)
    F_y = k_t h_y + B' (P_x - Q_x) + C' (P_y + Q_y)

``K[b]`` holds [C k_n, C k_t, C A, C B', C C', B] of block b and ``C`` the
factor on external forces, in the state's float type: no float literal
enters a loop, so float32 stays float32.  Row r's up and down neighbours of
column c are at columns c - 1 + s and c + s, with s = 0 or 1 by the row's x
offset.

Loops index 1D views from 0 (``for k in range(n)``): indices a compiler can
prove non-negative, so the loop vectorises.  A node is always updated by the
same kernel, whichever rank or task runs it, so results do not depend on the
decomposition.
"""
from numba import njit

from .floats import like

# Bits of the neighbour mask: right, up-right, up-left, left, down-left, down-right.
R_, UR_, UL_, L_, DL_, DR_ = 1, 2, 4, 8, 16, 32
# Columns of a block's row of constants K[b] (``engine.state.stiffness_constants`` fills them by these names);
# K_RATE: the gain g of ``rate_field`` (0 without the bonds' damping).
K_N, K_T, K_A, K_B, K_C, K_DAMP, K_RATE = range(7)
K_SIZE = 7


@njit(cache=True, inline="always", _nrt=False, fastmath={"contract"})
def _full(ux, uy, xm, xp, ym, yp, xur, xdl, xul, xdr, yur, ydl, yul, ydr, kn, kt, a, b, c):
    """C F of an interior node: each bond's difference first, then the pairs that share a stiffness."""
    hx, hy = (xm - ux) + (xp - ux), (ym - uy) + (yp - uy)
    qpx, qpy = (xur - ux) + (xdl - ux), (yur - uy) + (ydl - uy)
    qqx, qqy = (xul - ux) + (xdr - ux), (yul - uy) + (ydr - uy)
    return (kn * hx + a * (qpx + qqx) + b * (qpy - qqy),
            kt * hy + b * (qpx - qqx) + c * (qpy + qqy))


@njit(cache=True, inline="always", _nrt=False)
def drag(acc, j, sd, dx, dy):
    """Column j's running total of the body drag += sd |d|^2 (m c^2), d = u(t+dt) - u(t-dt), kept as two
    floats by an error-free two-sum (``kernels.budget.add``; written out here so that no FMA enters it)."""
    v = sd * (float(dx) * float(dx) + float(dy) * float(dy))
    a = acc[0, j]
    t = a + v
    bp = t - a
    acc[1, j] += (a - (t - bp)) + (v - bp)
    acc[0, j] = t


@njit(cache=True, inline="always", _nrt=False, fastmath={"contract"})
def row_full(cx, cy, zx, zy, px, py, r, j0, n, s, K, blk, damped, acc, sd):
    """Interior row segment: all six bonds, no external force.  Writes u(t+dt) into px, py; the bond
    forces are those of the field (zx, zy) (u(t) itself, or with the bonds' damping ``rate_field``).
    With the body drag, each node's dissipation sd |u(t+dt) - u(t-dt)|^2 (sd = zeta/(4 dt)) is added to
    its column's running total in ``acc`` (``kernels.budget``)."""
    kn, kt, a, b, c, bb = K[blk, K_N], K[blk, K_T], K[blk, K_A], K[blk, K_B], K[blk, K_C], K[blk, K_DAMP]
    xm, x0, xp = zx[r, j0 - 1:j0 - 1 + n], zx[r, j0:j0 + n], zx[r, j0 + 1:j0 + 1 + n]
    ym, y0, yp = zy[r, j0 - 1:j0 - 1 + n], zy[r, j0:j0 + n], zy[r, j0 + 1:j0 + 1 + n]
    xul, xur = zx[r + 1, j0 - 1 + s:j0 - 1 + s + n], zx[r + 1, j0 + s:j0 + s + n]
    yul, yur = zy[r + 1, j0 - 1 + s:j0 - 1 + s + n], zy[r + 1, j0 + s:j0 + s + n]
    xdl, xdr = zx[r - 1, j0 - 1 + s:j0 - 1 + s + n], zx[r - 1, j0 + s:j0 + s + n]
    ydl, ydr = zy[r - 1, j0 - 1 + s:j0 - 1 + s + n], zy[r - 1, j0 + s:j0 + s + n]
    cx0, cy0 = cx[r, j0:j0 + n], cy[r, j0:j0 + n]
    ox, oy = px[r, j0:j0 + n], py[r, j0:j0 + n]
    # Two copies of the loop, so neither holds a branch: with zeta = 0 the damping factor is skipped.
    if damped:
        for k in range(n):
            ux, uy = cx0[k], cy0[k]
            fx, fy = _full(x0[k], y0[k], xm[k], xp[k], ym[k], yp[k], xur[k], xdl[k], xul[k], xdr[k], yur[k],
                           ydl[k], yul[k], ydr[k], kn, kt, a, b, c)
            qx, qy = ox[k], oy[k]
            nx = ux + (bb * (ux - qx) + fx)
            ny = uy + (bb * (uy - qy) + fy)
            ox[k] = nx
            oy[k] = ny
            drag(acc, j0 + k, sd, nx - qx, ny - qy)
    else:
        for k in range(n):
            ux, uy = cx0[k], cy0[k]
            fx, fy = _full(x0[k], y0[k], xm[k], xp[k], ym[k], yp[k], xur[k], xdl[k], xul[k], xdr[k], yur[k],
                           ydl[k], yul[k], ydr[k], kn, kt, a, b, c)
            ox[k] = ux + ((ux - ox[k]) + fx)
            oy[k] = uy + ((uy - oy[k]) + fy)


@njit(cache=True, inline="always", _nrt=False, fastmath={"contract"})
def row_edge(cx, cy, zx, zy, px, py, r, j0, n, s, K, blk, damped, up, cf, ex, ey, gx, gy, acc, sd):
    """Row segment of a block's top row (``up`` False: no up bonds) or bottom row (``up`` True: no down bonds).

    Adds C (ex + gx, ey + gy): the per-column external force (ex, ey), e.g.
    interface bonds, and the uniform one (gx, gy), e.g. the normal load.
    """
    kn, kt, a, b, c, bb = K[blk, K_N], K[blk, K_T], K[blk, K_A], K[blk, K_B], K[blk, K_C], K[blk, K_DAMP]
    rr = r + 1 if up else r - 1
    xm, x0, xp = zx[r, j0 - 1:j0 - 1 + n], zx[r, j0:j0 + n], zx[r, j0 + 1:j0 + 1 + n]
    ym, y0, yp = zy[r, j0 - 1:j0 - 1 + n], zy[r, j0:j0 + n], zy[r, j0 + 1:j0 + 1 + n]
    cx0, cy0 = cx[r, j0:j0 + n], cy[r, j0:j0 + n]
    # The diagonal neighbour at c - 1 + s and the one at c + s.  Up: UL (K_UL) and UR (K_UR);
    # down: DL (K_UR) and DR (K_UL).  ``p`` is the one along K_UR, ``q`` along K_UL.
    xa, xb = zx[rr, j0 - 1 + s:j0 - 1 + s + n], zx[rr, j0 + s:j0 + s + n]
    ya, yb = zy[rr, j0 - 1 + s:j0 - 1 + s + n], zy[rr, j0 + s:j0 + s + n]
    exs, eys = ex[j0:j0 + n], ey[j0:j0 + n]
    ox, oy = px[r, j0:j0 + n], py[r, j0:j0 + n]
    if up:
        xp_, xq_, yp_, yq_ = xb, xa, yb, ya
    else:
        xp_, xq_, yp_, yq_ = xa, xb, ya, yb
    one = like(1, bb)
    damp = bb if damped else one
    for k in range(n):
        zx0, zy0 = x0[k], y0[k]
        hx, hy = (xm[k] - zx0) + (xp[k] - zx0), (ym[k] - zy0) + (yp[k] - zy0)
        dpx, dpy = xp_[k] - zx0, yp_[k] - zy0
        dqx, dqy = xq_[k] - zx0, yq_[k] - zy0
        fx = kn * hx + a * (dpx + dqx) + b * (dpy - dqy) + cf * (exs[k] + gx)
        fy = kt * hy + b * (dpx - dqx) + c * (dpy + dqy) + cf * (eys[k] + gy)
        ux, uy = cx0[k], cy0[k]
        qx, qy = ox[k], oy[k]
        nx = ux + (damp * (ux - qx) + fx)
        ny = uy + (damp * (uy - qy) + fy)
        ox[k] = nx
        oy[k] = ny
        if damped:
            drag(acc, j0 + k, sd, nx - qx, ny - qy)


@njit(cache=True, inline="always", _nrt=False, fastmath={"contract"})
def node_masked(cx, cy, zx, zy, px, py, r, j, s, K, blk, damped, mask, cf, fx, fy, acc, sd):
    """One node with only the bonds in ``mask`` (block edges), plus C times the external force (fx, fy).

    Without branches: a missing neighbour is read from the zero ghost cells
    around the block (or a real cell) and its difference weighed by 0.
    """
    kn, kt, a, b, c, bb = K[blk, K_N], K[blk, K_T], K[blk, K_A], K[blk, K_B], K[blk, K_C], K[blk, K_DAMP]
    ux, uy = cx[r, j], cy[r, j]
    vx, vy = zx[r, j], zy[r, j]
    wr, wur, wul = like(mask & R_, ux), like((mask & UR_) >> 1, ux), like((mask & UL_) >> 2, ux)
    wl, wdl, wdr = like((mask & L_) >> 3, ux), like((mask & DL_) >> 4, ux), like((mask & DR_) >> 5, ux)
    hx = wl * (zx[r, j - 1] - vx) + wr * (zx[r, j + 1] - vx)
    hy = wl * (zy[r, j - 1] - vy) + wr * (zy[r, j + 1] - vy)
    # Along K_UR: up-right and down-left; along K_UL: up-left and down-right.
    dpx = wur * (zx[r + 1, j + s] - vx) + wdl * (zx[r - 1, j - 1 + s] - vx)
    dpy = wur * (zy[r + 1, j + s] - vy) + wdl * (zy[r - 1, j - 1 + s] - vy)
    dqx = wul * (zx[r + 1, j - 1 + s] - vx) + wdr * (zx[r - 1, j + s] - vx)
    dqy = wul * (zy[r + 1, j - 1 + s] - vy) + wdr * (zy[r - 1, j + s] - vy)
    gx = kn * hx + a * (dpx + dqx) + b * (dpy - dqy) + cf * fx
    gy = kt * hy + b * (dpx - dqx) + c * (dpy + dqy) + cf * fy
    damp = bb if damped else like(1, bb)
    qx, qy = px[r, j], py[r, j]
    nx = ux + (damp * (ux - qx) + gx)
    ny = uy + (damp * (uy - qy) + gy)
    px[r, j] = nx
    py[r, j] = ny
    if damped:
        drag(acc, j, sd, nx - qx, ny - qy)


@njit(cache=True, _nrt=False, fastmath={"contract"})
def rate_field(cx, cy, px, py, zx, zy, g):
    """z = u(t) + g (u(t) - u(t-dt)) over a whole block (HALO copies and ghost cells included), g = beta/dt:
    the field whose bond forces are the elastic force plus the bonds' damping beta K (u' as
    (u(t) - u(t-dt))/dt), so one stencil pass gives both (``model.damping``, form "bonds")."""
    for r in range(cx.shape[0]):
        ax, ay, bx, by, ox, oy = cx[r], cy[r], px[r], py[r], zx[r], zy[r]
        for j in range(ax.shape[0]):
            ox[j] = ax[j] + g * (ax[j] - bx[j])
            oy[j] = ay[j] + g * (ay[j] - by[j])
