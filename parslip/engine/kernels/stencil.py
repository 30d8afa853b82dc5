"""The bulk Born update of a node: bond forces fused with damped Verlet (interior rows: ``kernels.rect``).

Responsible for the arithmetic of a node update only; which rows and columns
to update comes from the row schedule (``parallel.layout``).

Each block is stored as 2D arrays [row, column] of the displacements from
the reference lattice, x and y apart, at two Verlet levels.  A step reads
level ``c`` (u(t)) and overwrites level ``p`` (u(t - dt)) with u(t + dt):

    u(t+dt) = (2 u(t) - (1 - zeta dt/2) u(t-dt) + dt^2 F(t)) / (1 + zeta dt/2)
            = u(t) + B (u(t) - u(t-dt)) + C F(t),
    B = (1 - zeta dt/2)/(1 + zeta dt/2),  C = dt^2/(1 + zeta dt/2),

the second form adding a small increment to u, never forming 2u - u_old;
with zeta = 0, B = 1 exactly and multiplying by it changes no bit (fma(1, d, f) rounds as d + f), so the
kernels take B as a value and their ``damped`` flag only describes the step.  F is the
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

from .exact import quant
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


@njit(cache=True, forceinline=True, _nrt=False, fastmath={"contract"})
def budget_shares(ux, uy, qx, qy, nx, ny, gx, gy, cs, drag, energy):
    """A node's exact shares of the budget (``kernels.exact``, in quanta) after its update u(t-dt) = q ->
    u(t+dt) = n from u(t): with ``drag`` the body drag of the step, sd |n - q|^2 (``output.energy =
    "checked"``; the bonds' dashpots are never summed here: ``kernels.budget``); in a step that ends on a frame, |n - u|^2 / (2 dt^2) and the bulk elastic
    -1/2 n . C F(u) / C with C F(u) = (gx, gy), which sum to H(t + dt/2).  ``cs`` holds the factors with
    each term's scale in them (``Budget.cs``)."""
    d = 0
    k = 0
    e = 0
    if drag:
        dx, dy = float(nx) - float(qx), float(ny) - float(qy)
        d = quant((dx * dx + dy * dy) * cs[0])
    if energy:
        vx, vy = float(nx) - float(ux), float(ny) - float(uy)
        k = quant((vx * vx + vy * vy) * cs[2])
        e = quant((float(nx) * float(gx) + float(ny) * float(gy)) * cs[3])
    return d, k, e


@njit(cache=True, inline="always", _nrt=False, fastmath={"contract"})
def _edge_force(zx, zy, xm, x0, xp, ym, y0, yp, xp_, xq_, yp_, yq_, k, kn, kt, a, b, c):
    """C F of a node of a block's top or bottom row, without external force (``row_edge``)."""
    zx0, zy0 = x0[k], y0[k]
    hx, hy = (xm[k] - zx0) + (xp[k] - zx0), (ym[k] - zy0) + (yp[k] - zy0)
    dpx, dpy = xp_[k] - zx0, yp_[k] - zy0
    dqx, dqy = xq_[k] - zx0, yq_[k] - zy0
    return (kn * hx + a * (dpx + dqx) + b * (dpy - dqy),
            kt * hy + b * (dpx - dqx) + c * (dpy + dqy))


@njit(cache=True, inline="always", _nrt=False, fastmath={"contract"})
def _views(zx, zy, r, rr, j0, n, s, up):
    """The neighbour views of a top (``up`` False) or bottom (``up`` True) row segment of the field z: same
    row left, centre, right, and the diagonal pair, ``p`` along K_UR and ``q`` along K_UL."""
    xm, x0, xp = zx[r, j0 - 1:j0 - 1 + n], zx[r, j0:j0 + n], zx[r, j0 + 1:j0 + 1 + n]
    ym, y0, yp = zy[r, j0 - 1:j0 - 1 + n], zy[r, j0:j0 + n], zy[r, j0 + 1:j0 + 1 + n]
    # The diagonal neighbour at c - 1 + s and the one at c + s.  Up: UL (K_UL) and UR (K_UR);
    # down: DL (K_UR) and DR (K_UL).
    xa, xb = zx[rr, j0 - 1 + s:j0 - 1 + s + n], zx[rr, j0 + s:j0 + s + n]
    ya, yb = zy[rr, j0 - 1 + s:j0 - 1 + s + n], zy[rr, j0 + s:j0 + s + n]
    if up:
        return xm, x0, xp, ym, y0, yp, xb, xa, yb, ya
    return xm, x0, xp, ym, y0, yp, xa, xb, ya, yb


# Not inlined: a call per row segment of a block's edge rows, a few rows of many.
@njit(cache=True, _nrt=False, fastmath={"contract"})
def row_edge(cx, cy, zx, zy, px, py, r, j0, n, s, K, blk, damped, up, cf, ex, ey, gx, gy, drag, rated, energy,
             cs):
    """Row segment of a block's top row (``up`` False: no up bonds) or bottom row (``up`` True: no down bonds).

    Adds C (ex + gx, ey + gy): the per-column external force (ex, ey), e.g.
    interface bonds, and the uniform one (gx, gy), e.g. the normal load.
    Returns the segment's exact shares of the budget (``budget_shares``; the bulk forces alone).
    """
    kn, kt, a, b, c, bb = K[blk, K_N], K[blk, K_T], K[blk, K_A], K[blk, K_B], K[blk, K_C], K[blk, K_DAMP]
    rr = r + 1 if up else r - 1
    xm, x0, xp, ym, y0, yp, xp_, xq_, yp_, yq_ = _views(zx, zy, r, rr, j0, n, s, up)
    um, u0, up_, vm, v0, vp, up2, uq2, vp2, vq2 = _views(cx, cy, r, rr, j0, n, s, up)
    exs, eys = ex[j0:j0 + n], ey[j0:j0 + n]
    ox, oy = px[r, j0:j0 + n], py[r, j0:j0 + n]
    ds = 0
    ks = 0
    es = 0
    for k in range(n):
        fx, fy = _edge_force(zx, zy, xm, x0, xp, ym, y0, yp, xp_, xq_, yp_, yq_, k, kn, kt, a, b, c)
        ux, uy = u0[k], v0[k]
        qx, qy = ox[k], oy[k]
        nx = ux + (bb * (ux - qx) + (fx + cf * (exs[k] + gx)))
        ny = uy + (bb * (uy - qy) + (fy + cf * (eys[k] + gy)))
        ox[k] = nx
        oy[k] = ny
        if drag or energy:
            hx, hy = fx, fy
            if rated and energy:
                hx, hy = _edge_force(cx, cy, um, u0, up_, vm, v0, vp, up2, uq2, vp2, vq2, k, kn, kt, a, b, c)
            d, kk, e = budget_shares(ux, uy, qx, qy, nx, ny, hx, hy, cs, drag, energy)
            ds += d
            ks += kk
            es += e
    return ds, ks, es


@njit(cache=True, forceinline=True, _nrt=False, fastmath={"contract"})
def masked_force(zx, zy, r, j, s, K, blk, mask):
    """C F of node (r, j) from the field (zx, zy), with only the bonds in ``mask``.

    Without branches: a missing neighbour is read from the zero ghost cells
    around the block (or a real cell) and its difference weighed by 0.
    """
    kn, kt, a, b, c = K[blk, K_N], K[blk, K_T], K[blk, K_A], K[blk, K_B], K[blk, K_C]
    vx, vy = zx[r, j], zy[r, j]
    wr, wur, wul = like(mask & R_, vx), like((mask & UR_) >> 1, vx), like((mask & UL_) >> 2, vx)
    wl, wdl, wdr = like((mask & L_) >> 3, vx), like((mask & DL_) >> 4, vx), like((mask & DR_) >> 5, vx)
    hx = wl * (zx[r, j - 1] - vx) + wr * (zx[r, j + 1] - vx)
    hy = wl * (zy[r, j - 1] - vy) + wr * (zy[r, j + 1] - vy)
    # Along K_UR: up-right and down-left; along K_UL: up-left and down-right.
    dpx = wur * (zx[r + 1, j + s] - vx) + wdl * (zx[r - 1, j - 1 + s] - vx)
    dpy = wur * (zy[r + 1, j + s] - vy) + wdl * (zy[r - 1, j - 1 + s] - vy)
    dqx = wul * (zx[r + 1, j - 1 + s] - vx) + wdr * (zx[r - 1, j + s] - vx)
    dqy = wul * (zy[r + 1, j - 1 + s] - vy) + wdr * (zy[r - 1, j + s] - vy)
    return (kn * hx + a * (dpx + dqx) + b * (dpy - dqy),
            kt * hy + b * (dpx - dqx) + c * (dpy + dqy))


@njit(cache=True, forceinline=True, _nrt=False, fastmath={"contract"})
def node_masked(cx, cy, zx, zy, px, py, r, j, s, K, blk, damped, mask, cf, fx, fy, drag, rated, energy, cs):
    """One node with only the bonds in ``mask`` (block edges), plus C times the external force (fx, fy).
    Returns its exact shares of the budget (``budget_shares``)."""
    bb = K[blk, K_DAMP]
    ux, uy = cx[r, j], cy[r, j]
    gx, gy = masked_force(zx, zy, r, j, s, K, blk, mask)
    qx, qy = px[r, j], py[r, j]
    nx = ux + (bb * (ux - qx) + (gx + cf * fx))
    ny = uy + (bb * (uy - qy) + (gy + cf * fy))
    px[r, j] = nx
    py[r, j] = ny
    if not (drag or energy):
        return 0, 0, 0
    hx, hy = gx, gy
    if rated and energy:
        hx, hy = masked_force(cx, cy, r, j, s, K, blk, mask)
    return budget_shares(ux, uy, qx, qy, nx, ny, hx, hy, cs, drag, energy)


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
