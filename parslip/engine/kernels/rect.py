"""The bulk update of a rectangle of interior rows: consecutive rows of a block with every bond present, over
the same columns, in one call.

Responsible for the loop over rows and the views each row needs; the arithmetic of a node is the row
kernel's (``stencil._full`` and the damped Verlet step of ``stencil``'s docstring), term for term, so a node
gets the same bits whichever kernel updates it and however the schedule groups its rows.

A task of the schedule (``parallel.layout._tasks``) that covers rows r0 .. r0 + rows - 1 over columns
[j0, j0 + n) costs one dispatch, and each row three views of the field per coordinate (its own row from
j0 - 1, the rows above and below from j0 - 1 + s) where a row on its own took seven: the fixed cost of a
row, about 55 ns when each row was a task of its own (``studies.bench.rows``), was mostly the views and
the checks the vectorised loop makes that they do not overlap what it writes.  Row r0 + i has shift
s = s0 ^ (i & 1): the rows' x offsets alternate.
"""
import numpy as np
from numba import njit

from .exact import quant
from .stencil import K_A, K_B, K_C, K_DAMP, K_N, K_T, _full


@njit(cache=True, inline="always", _nrt=False)      # returns views: numba inlines it (no call returns a view)
def _row_views(fx, fy, r, j0, n, s):
    """The views of a field (fx, fy) that row r's nodes j0 .. j0 + n - 1 read: row r from column j0 - 1 (left,
    centre, right at k, k + 1, k + 2), the rows above and below from j0 - 1 + s (up-left and up-right at k,
    k + 1; down-left and down-right likewise); x then y of each."""
    return (fx[r, j0 - 1:j0 + 1 + n], fy[r, j0 - 1:j0 + 1 + n],
            fx[r + 1, j0 - 1 + s:j0 + s + n], fy[r + 1, j0 - 1 + s:j0 + s + n],
            fx[r - 1, j0 - 1 + s:j0 + s + n], fy[r - 1, j0 - 1 + s:j0 + s + n])


@njit(cache=True, inline="always", _nrt=False, fastmath={"contract"})
def _node(xh, yh, xu, yu, xd, yd, ch, dh, ox, oy, k, kn, kt, a, b, c, bb, rated):
    """Node k of a row: C F from z (the views of ``_row_views``), u(t) (from c with the bonds' dashpots, else
    z is u) and u(t+dt) = u + (B (u - q) + C F) written over q = u(t-dt) in (ox, oy).  Returns u, q, the new
    u and C F, for the sums.  B = 1 exactly without the body drag: 1 (u - q) + f, even contracted to
    fma(1, u - q, f), rounds as (u - q) + f, so the undamped loops need no version of their own."""
    fx, fy = _full(xh[k + 1], yh[k + 1], xh[k], xh[k + 2], yh[k], yh[k + 2], xu[k + 1], xd[k], xu[k],
                   xd[k + 1], yu[k + 1], yd[k], yu[k], yd[k + 1], kn, kt, a, b, c)
    if rated:
        ux, uy = ch[k + 1], dh[k + 1]
    else:
        ux, uy = xh[k + 1], yh[k + 1]
    qx, qy = ox[k], oy[k]
    nx = ux + (bb * (ux - qx) + fx)
    ny = uy + (bb * (uy - qy) + fy)
    ox[k] = nx
    oy[k] = ny
    return ux, uy, qx, qy, nx, ny, fx, fy


@njit(cache=True, forceinline=True, _nrt=False, fastmath={"contract"})
def _rect_loop(cx, cy, zx, zy, px, py, r0, rows, j0, n, s0, kn, kt, a, b, c, bb, rated):
    """The loop of ``rect_full`` in a step that sums nothing, for a constant ``rated``: one branch-free,
    vectorised loop each.  Without the bonds' dashpots z is u, so u is read once, from z."""
    for i in range(rows):
        r = r0 + i
        s = s0 ^ (i & 1)
        xh, yh, xu, yu, xd, yd = _row_views(zx, zy, r, j0, n, s)
        ch, dh = cx[r, j0 - 1:j0 + 1 + n], cy[r, j0 - 1:j0 + 1 + n]
        ox, oy = px[r, j0:j0 + n], py[r, j0:j0 + n]
        for k in range(n):
            _node(xh, yh, xu, yu, xd, yd, ch, dh, ox, oy, k, kn, kt, a, b, c, bb, rated)


@njit(cache=True, forceinline=True, _nrt=False, fastmath={"contract"})
def _rect_sums(cx, cy, zx, zy, px, py, r0, rows, j0, n, s0, kn, kt, a, b, c, bb, cs, rated, wd, we):
    """The loop of ``rect_full`` in a step that sums (a frame's, or every step with ``output.energy =
    "checked"``), for a constant ``rated``: the same update, and the exact shares of ``stencil.budget_shares``
    weighed by wd (the body drag's) and we (the frame's kinetic and elastic energy), each 0 or 1, so one loop
    serves every such step without a branch.  With the bonds' dashpots the elastic share takes C F(u) from u
    itself, not from z."""
    ds = 0
    ks = 0
    es = 0
    for i in range(rows):
        r = r0 + i
        s = s0 ^ (i & 1)
        xh, yh, xu, yu, xd, yd = _row_views(zx, zy, r, j0, n, s)
        ch, dh, cu, du, cd, dd = _row_views(cx, cy, r, j0, n, s)
        ox, oy = px[r, j0:j0 + n], py[r, j0:j0 + n]
        for k in range(n):
            ux, uy, qx, qy, nx, ny, gx, gy = _node(xh, yh, xu, yu, xd, yd, ch, dh, ox, oy, k, kn, kt, a, b, c, bb,
                                                   rated)
            if rated:
                gx, gy = _full(ux, uy, ch[k], ch[k + 2], dh[k], dh[k + 2], cu[k + 1], cd[k], cu[k], cd[k + 1],
                               du[k + 1], dd[k], du[k], dd[k + 1], kn, kt, a, b, c)
            dx, dy = float(nx) - float(qx), float(ny) - float(qy)
            vx, vy = float(nx) - float(ux), float(ny) - float(uy)
            ds += wd * quant((dx * dx + dy * dy) * cs[0])
            ks += we * quant((vx * vx + vy * vy) * cs[2])
            es += we * quant((float(nx) * float(gx) + float(ny) * float(gy)) * cs[3])
    return ds, ks, es


@njit(cache=True, forceinline=True, _nrt=False, fastmath={"contract"})
def rect_full(cx, cy, zx, zy, px, py, r0, rows, j0, n, s0, K, blk, damped, drag, rated, energy, cs):
    """Interior rows r0 .. r0 + rows - 1 over columns [j0, j0 + n): all six bonds, no external force, as
    each row as a block's interior row.  Writes u(t+dt) into px, py; returns the rectangle's exact shares of the
    budget (damping, kinetic, elastic)."""
    kn, kt, a, b, c, bb = K[blk, K_N], K[blk, K_T], K[blk, K_A], K[blk, K_B], K[blk, K_C], K[blk, K_DAMP]
    # Four loops: the steps that sum nothing (all but a frame's, unless output.energy = "checked") run one of
    # two without sums, the others one of two with the sums weighed by 0 or 1 (as the flags say), each
    # branch-free and vectorised.  A loop per combination of (rated, drag, energy) made six, at 1.6 s of
    # compile each (push on 1 rank, 2026-11-27); weighing the sums saves two of them, at no measurable cost
    # per step.  A single loop with sums, reading u and z apart, compares more addresses than the vectoriser
    # checks at run time, and ran scalar: 28 % slower per step on the README's main job.  The update is the
    # same expression in each, so its bits do not depend on which loop ran.  The bonds' dashpots and the
    # body drag never act together (``damped`` only describes the step: B is a value, 1 without the drag).
    if drag or energy:
        wd, we = np.int64(drag), np.int64(energy)
        if rated:
            return _rect_sums(cx, cy, zx, zy, px, py, r0, rows, j0, n, s0, kn, kt, a, b, c, bb, cs, True, wd, we)
        return _rect_sums(cx, cy, zx, zy, px, py, r0, rows, j0, n, s0, kn, kt, a, b, c, bb, cs, False, wd, we)
    if rated:
        _rect_loop(cx, cy, zx, zy, px, py, r0, rows, j0, n, s0, kn, kt, a, b, c, bb, True)
    else:
        _rect_loop(cx, cy, zx, zy, px, py, r0, rows, j0, n, s0, kn, kt, a, b, c, bb, False)
    return 0, 0, 0
