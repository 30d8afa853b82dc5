"""Interface bonds: break, re-form, forces, and the per-frame record of the interface.

Responsible for the arithmetic of the adhesive bonds between the block's
bottom row (the top interface sites, one per column) and the substrate's top
row (the bottom sites).  Positions are x = column + u on both rows (no row
offset there).  For a top site at column g bonded to bottom site q:

    x_ij = (g - q) + (u_x,top - u_x,bottom),   y_ij = delta0 + (u_y,top - u_y,bottom)
    force on the top node:  f_x = -k_x (x_ij - x0),  f_y = -k_y (y_ij - delta0)

and the opposite force on the bottom node.  Each step, at positions u(t):

1. a bond breaks when its length sqrt(x_ij^2 + y_ij^2) reaches delta_b;
2. each free top site claims the nearest free bottom site within delta0
   (ties: lower bottom index), looking at the substrate columns within
   ``window`` of its nearest one (``P_REBOND`` replaces delta0 here; with
   ``P_FACING`` it looks at the nearest column only);
3. claims are granted in increasing top-site order, so when two free top
   sites reach the same bottom site the lower global index wins and the
   other waits a step; a re-formed bond takes x0 = x_ij then (starts
   unstressed in x), or 0 with ``reform_zero``.

Every rank runs this over all its interface sites, OWNED and HALO, in global
order: HALO copies arrive with their bond state each step, so a rank's own
sites, and the halo sites bonded to its own substrate sites, come out exact
as long as the halo covers the distances the update depends on
(``layout.Reach``).  ``coverage`` checks that in the current positions.
"""
import numpy as np
from numba import njit

from .floats import like

# Counters (owned events) and flags (a nonzero flag stops the run; see loop.FLAG_*).
BREAKS, FORMS = 0, 1

# Indices into the integer geometry ``g`` of the interface (local columns unless said).
(G_TBASE, G_TLO, G_THI, G_TOWN0, G_TOWN1, G_BBASE, G_BLO, G_BHI, G_BOWN0, G_BOWN1, G_BROW, G_WINDOW,
 G_TFIRST, G_TLAST, G_BCOLS, G_RIGID, G_TCOVER, G_BCOVER) = range(18)
G_SIZE = 18
# Indices into the float constants ``p`` (state float type).
# P_REBOND: the largest length at which a free site re-bonds (delta0 unless ``interface.rebond_within``);
# P_FACING: nonzero to re-bond only to the facing substrate site (the nearest column), not the nearest free one.
P_DELTA0, P_DELTAB, P_KX, P_KY, P_REFORM_ZERO, P_DRIFT, P_INV_L, P_TRACTION, P_REBOND, P_FACING = range(10)
P_SIZE = 10


@njit(cache=True, inline="always", _nrt=False)
def _gap(g, q, tx, ty, bx, by, j, i, d0):
    """(x_ij, y_ij) of top site at local column j (global g) and bottom site local i (global q)."""
    return like(g - q, d0) + (tx[j] - bx[i]), d0 + (ty[j] - by[i])


@njit(cache=True, _nrt=False)
def update(tx, ty, bx, by, partner, x0, taken, claim, g, p, counters, reach, ext_x, ext_y, exb_x, exb_y):
    """Steps 1-3 above on every local top site, then the bond forces at u(t).

    tx, ty: the block's row 0 at u(t); bx, by: the substrate's interface row.  ``partner`` holds global
    bottom columns (-1: broken), indexed by local top column.  Forces go on OWNED top nodes into
    (ext_x, ext_y) and on OWNED bottom nodes into (exb_x, exb_y), both by local column, zero where
    there is no bond.  ``claim`` is scratch: the free sites, then their claims.

    ``reach[0]`` becomes the global column of the first OWNED top site whose bond or re-bonding
    window reaches past this rank's substrate copies (a bond out of reach), else stays -1.
    """
    tbase, tlo, thi, town0, town1 = g[G_TBASE], g[G_TLO], g[G_THI], g[G_TOWN0], g[G_TOWN1]
    bbase, blo, bhi, bcols, w = g[G_BBASE], g[G_BLO], g[G_BHI], g[G_BCOLS], g[G_WINDOW]
    bown0, bown1 = g[G_BOWN0], g[G_BOWN1]
    d0, db, kx, ky = p[P_DELTA0], p[P_DELTAB], p[P_KX], p[P_KY]
    db2, d02 = db * db, p[P_REBOND] * p[P_REBOND]
    if p[P_FACING] != 0:
        w = 0
    zero = like(0, d0)
    for i in range(blo, bhi):
        taken[i] = 0
    for i in range(bown0, bown1):
        exb_x[i] = zero
        exb_y[i] = zero
    # 1. Breaks; the bonds that hold mark their substrate site taken and apply their force now (the
    #    positions do not change within the step).  Free sites are listed in ``claim``.
    nfree = 0
    for j in range(tlo, thi):
        q = partner[j]
        top_own = town0 <= j < town1
        if top_own:
            ext_x[j] = zero
            ext_y[j] = zero
        if q >= 0:
            i = q - bbase
            if i < blo or i >= bhi:
                if top_own and reach[0] < 0:
                    reach[0] = j + tbase
                continue
            dx, dy = _gap(j + tbase, q, tx, ty, bx, by, j, i, d0)
            if dx * dx + dy * dy < db2:
                taken[i] = 1
                _apply(j, i, dx, dy, x0, top_own, bown0, bown1, d0, kx, ky, ext_x, ext_y, exb_x, exb_y)
                continue
            partner[j] = -1
            if top_own:
                counters[BREAKS] += 1
        claim[nfree] = j
        nfree += 1
    # 2. Claims of the free sites, kept in their slot m of ``claim`` (their site is claim_site[m]).
    for m in range(nfree):
        j = claim[m]
        gl = j + tbase
        qc = np.int64(np.floor(like(gl, d0) + tx[j] + 0.5))    # nearest substrate column
        best = np.inf
        got = -1
        for q in range(qc - w, qc + w + 1):
            if q < 0 or q >= bcols:
                continue
            i = q - bbase
            if i < blo or i >= bhi:
                if town0 <= j < town1 and reach[0] < 0:
                    reach[0] = gl
                continue
            if taken[i]:
                continue
            dx, dy = _gap(gl, q, tx, ty, bx, by, j, i, d0)
            d2 = dx * dx + dy * dy
            if d2 <= d02 and d2 < best:
                best = d2
                got = i
        claim[m] = got * (thi + 1) + j if got >= 0 else -1 - j        # site and claim in one integer
    # 3. Grants in increasing site order (the free list is in site order); a new bond's force applies at once.
    zero_x0 = p[P_REFORM_ZERO] != 0
    for m in range(nfree):
        c = claim[m]
        if c < 0:
            continue
        i, j = c // (thi + 1), c % (thi + 1)
        if taken[i]:
            continue
        taken[i] = 1
        partner[j] = i + bbase
        dx, dy = _gap(j + tbase, i + bbase, tx, ty, bx, by, j, i, d0)
        x0[j] = zero if zero_x0 else dx
        top_own = town0 <= j < town1
        _apply(j, i, dx, dy, x0, top_own, bown0, bown1, d0, kx, ky, ext_x, ext_y, exb_x, exb_y)
        if top_own:
            counters[FORMS] += 1


@njit(cache=True, inline="always", _nrt=False)
def _apply(j, i, dx, dy, x0, top_own, bown0, bown1, d0, kx, ky, ext_x, ext_y, exb_x, exb_y):
    """The bond's force f_x = -k_x (x_ij - x0), f_y = -k_y (y_ij - delta0) on its OWNED ends."""
    bot_own = bown0 <= i < bown1
    if top_own or bot_own:
        fx = -kx * (dx - x0[j])
        fy = -ky * (dy - d0)
        if top_own:
            ext_x[j] = fx
            ext_y[j] = fy
        if bot_own:
            exb_x[i] = -fx
            exb_y[i] = -fy


@njit(cache=True, _nrt=False)
def coverage(tx, bx, g):
    """True when this rank's interface copies reach far enough in the current positions (``layout.Reach``).

    The region of interest is this rank's own substrate sites and the current x of its own top sites;
    the block's interface row must be stored over it plus ``top_cover`` a, and the substrate's over it
    plus ``bottom_cover`` a, except where a row ends.  Top sites stay in x order along the row.
    """
    tbase, tlo, thi, town0, town1 = g[G_TBASE], g[G_TLO], g[G_THI], g[G_TOWN0], g[G_TOWN1]
    bbase, blo, bhi, bown0, bown1 = g[G_BBASE], g[G_BLO], g[G_BHI], g[G_BOWN0], g[G_BOWN1]
    if thi <= tlo:
        return True
    have = False
    lo = 0.0
    hi = 0.0
    if bown1 > bown0:
        lo, hi, have = float(bown0 + bbase), float(bown1 - 1 + bbase), True
    if town1 > town0:
        a = town0 + tbase + float(tx[town0])
        b = town1 - 1 + tbase + float(tx[town1 - 1])
        lo, hi = (min(lo, a), max(hi, b)) if have else (a, b)
        have = True
    if not have:
        return True
    ct, cb = g[G_TCOVER], g[G_BCOVER]
    if tlo + tbase > g[G_TFIRST] and tlo + tbase + float(tx[tlo]) > lo - ct:
        return False
    if thi - 1 + tbase < g[G_TLAST] and thi - 1 + tbase + float(tx[thi - 1]) < hi + ct:
        return False
    if blo + bbase > 0 and blo + bbase > lo - cb:
        return False
    if bhi - 1 + bbase < g[G_BCOLS] - 1 and bhi - 1 + bbase < hi + cb:
        return False
    return True


@njit(cache=True, _nrt=False)
def record(tx, ty, bx, by, partner, x0, g, p, k, f_intact, f_partner, f_ux, f_uy, f_sxy, f_syy):
    """Frame k of the interface record for the OWNED top sites: intact, partner, u/l, and the traction
    sxy = k_x (x_ij - x0) / (a rho c_r^2) = -f_x/(a rho c_r^2), syy = k_y (y_ij - delta0)/(a rho c_r^2)."""
    tbase, town0, town1 = g[G_TBASE], g[G_TOWN0], g[G_TOWN1]
    bbase, blo, bhi = g[G_BBASE], g[G_BLO], g[G_BHI]
    d0, kx, ky, inv_l, tr = p[P_DELTA0], p[P_KX], p[P_KY], p[P_INV_L], p[P_TRACTION]
    for m in range(town1 - town0):
        j = town0 + m
        q = partner[j]
        f_partner[k, m] = q
        f_intact[k, m] = 1 if q >= 0 else 0
        f_ux[k, m] = tx[j] * inv_l
        f_uy[k, m] = ty[j] * inv_l
        i = q - bbase
        if q >= 0 and blo <= i < bhi:
            dx, dy = _gap(j + tbase, q, tx, ty, bx, by, j, i, d0)
            f_sxy[k, m] = kx * (dx - x0[j]) * tr
            f_syy[k, m] = ky * (dy - d0) * tr
        else:
            f_sxy[k, m] = 0.0
            f_syy[k, m] = 0.0
