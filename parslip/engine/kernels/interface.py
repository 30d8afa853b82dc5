"""Interface bonds: break, re-form, forces, and the per-frame record of the interface.

Responsible for the arithmetic of the adhesive bonds between the block's
bottom row (the top interface sites, one per column) and the substrate's top
row (the bottom sites).  Positions are x = column + u on both rows (no row
offset there).  For a top site at column g bonded to bottom site q:

    x_ij = (g - q) + (u_x,top - u_x,bottom),   y_ij = delta0 + (u_y,top - u_y,bottom)
    force on the top node:  f_x = -k_x (x_ij - x0),  f_y = -k_y (y_ij - delta0)

and the opposite force on the bottom node.  Each step, at positions u(t):

1. a bond breaks when its length sqrt(x_ij^2 + y_ij^2) reaches delta_b; with
   slip weakening (``interface.softening``, a nucleation) it weakens from
   there and breaks once weakened to its residual (``_soften``);
2. each free top site claims the nearest free bottom site within the law's
   re-bonding length R (delta0 unless set; ties: lower bottom index), among
   the substrate sites whose current x lies within R + 1/2 (SEARCH_MARGIN) of its own
   (``_span``: found from where the substrate's sites are now, wherever
   they have drifted from their columns; REBOND_FACING takes only the one
   nearest in x);
3. claims are granted in increasing top-site order, so when two free top
   sites reach the same bottom site the lower global index wins and the
   other waits a step; a re-formed bond takes its rest offset by the rule
   ``_rest_offset`` (0, or x_ij: unstressed in x);
4. with a contact stiffness (``interface.contact``), each site still free
   is pushed off the substrate's surface, and with contact friction held by
   its stick spring along it (``_contacts``, ``_stick``); the energy budget
   counts each step's contact springs as springs the step re-formed
   (``kernels.budget``: ``_contacts_left`` takes off those of the step before).

The law's parameters and rule codes come from ``model.interface``; each rule
is one inlined function below, chosen by its code.

Every rank runs this over all its interface sites, OWNED and HALO, in global
order: HALO copies arrive with their bond state each step, so a rank's own
sites, and the halo sites bonded to its own substrate sites, come out exact
as long as the halo covers the distances the update depends on
(``layout.Reach``), measured in current positions: ``coverage`` checks that
every step.  The substrate's interface row must stay in x order (no site
passes its neighbour), which the loop checks; nothing else bounds how far
its sites drift from their columns.
"""
from collections import namedtuple

import numpy as np
from numba import njit

from ...model.interface import (BREAK, CAND, CLOCK, DELTA_B, FORM, HEAL_SPEED, HEAL_TIME, KX, KY, PARTNER, PEAK,
                                REBOND_FACING, REFORM_ZERO, SLIPPED, SOFTENING, SPENT, STICK, X0)
from ...parallel.codes import SEARCH_MARGIN
from . import budget as bg
from .floats import like

# Counters (owned events) and flags (a nonzero flag stops the run; see loop.FLAG_*).  The kinds of a bond
# event, BREAK and FORM, are the law's (``model.interface``).
BREAKS, FORMS = 0, 1

# The integer geometry of the interface on one rank (local array columns unless said):
#   tbase, bbase     global column of array column 0 of the block's / the substrate's interface row
#   tlo, thi         the block's interface sites stored here (OWNED and HALO), [tlo, thi)
#   town0, town1     the block's OWNED interface sites
#   blo, bhi         the substrate's interface sites stored here; bown0, bown1 the OWNED ones
#   brow             array row of the substrate's interface row
#   tfirst, tlast    global columns of the block's first and last interface site
#   bcols            substrate columns in all; rigid: 1 for a rigid substrate
#   tcover, bcover   reach (a) the halo must cover beyond this rank's interest (``layout.Reach``)
Geometry = namedtuple("Geometry", "tbase tlo thi town0 town1 bbase blo bhi bown0 bown1 brow tfirst tlast "
                                  "bcols rigid tcover bcover")
# Constants of the rank's interface record, in the state's float type: inv_l = 1/l; traction = 1/(a rho c_r^2);
# energy = 1/c_r^2 (an energy in m c^2 times it is in m c_r^2).
Constants = namedtuple("Constants", "inv_l traction energy")
# The interface arrays of one rank, indexed by local column of the block's interface row (top sites) or
# the substrate's (bottom sites): bonds, the per-site bond state [row, site] with the rows of
# ``model.interface.BOND_TABLE`` (partner: global substrate column, -1 broken; x0: rest offset; the site's
# own kx, ky, delta_b); rules, the law's scalars and rule codes (``model.interface.Rules``); claim and
# taken are scratch; ext_x/ext_y and exb_x/exb_y the bond forces on OWNED top and bottom nodes; zeros a
# row of zeros; counters [BREAKS, FORMS] of OWNED sites; reach[0] the first OWNED site out of the halo's
# reach (-1 none).
Iface = namedtuple("Iface", "bonds rules claim taken ext_x ext_y exb_x exb_y zeros geom consts counters reach "
                            "events")
# The event record of one rank: every break and re-formation of an OWNED top site, in the order the loop
# makes them (by step; within a step the breaks in site order, then the re-formations in site order):
#   step     the step n whose update made it (absolute, from the start of the ramp)
#   site     the global interface site (0 = the block's first column)
#   kind     BREAK or FORM
#   partner  the substrate column the bond left (BREAK) or joined (FORM)
#   energy   the bond's stored energy at that step, 1/2 k_x (x_ij - x0)^2 + 1/2 k_y (y_ij - delta0)^2 (m c_r^2),
#            at the positions u(n) it broke at (BREAK) or with the rest offset it formed with (FORM)
#   traction its shear traction then, k_x (x_ij - x0)/(a rho c_r^2) (rho c_r^2), as the frames' sxy
#   dissipated  the energy the bond's weakening took from its peak to its break (m c_r^2; ``_soften``: the
#            staggered form the budget's softening term sums), 0 for a bond that broke at its peak and for
#            a re-formation
#   count    count[0]: events held.  The caller sizes the arrays for the worst case between two agreements
#            of the ranks (2 events per OWNED site per step) and empties them before they can overflow.
# The stored energy and the traction take the bond's shear stiffness as it broke (``_bond_k``: k_x, or a
# weakening bond's secant).
Events = namedtuple("Events", "step site kind partner energy traction dissipated count")


# Inlined by numba: the step's kernels and the frames' call it, and a job compiles those on two ranks at
# once (engine.compile); compiled on its own, both would compile it.
@njit(cache=True, inline="always", _nrt=False)
def _gap(g, q, tx, ty, bx, by, j, i, d0):
    """(x_ij, y_ij) of top site at local column j (global g) and bottom site local i (global q)."""
    return like(g - q, d0) + (tx[j] - bx[i]), d0 + (ty[j] - by[i])


# --- The law's rules, one inlined function each, chosen by the law's codes -----------------------------

@njit(cache=True, forceinline=True, _nrt=False)
def _rest_offset(reform, dx, zero):
    """x0 of a bond that re-forms at x_ij = dx: 0 (REFORM_ZERO) or dx (REFORM_CURRENT)."""
    return zero if reform == REFORM_ZERO else dx


@njit(cache=True, forceinline=True, _nrt=False)
def _heals(rules, bonds, j, q, dvx):
    """Whether free site j may take its claim q (a substrate column; -1: none) this step, by the healing
    rule's bits: HEAL_SPEED while its x-displacement relative to q over the last step, ``dvx``, is below
    heal_speed dt; HEAL_TIME once q has been its claim for more than n_heal consecutive steps (the clock
    restarts whenever the claim changes or lapses)."""
    ok = True
    if rules.heal & HEAL_SPEED:
        ok = q >= 0 and abs(dvx) < rules.heal_du
    if rules.heal & HEAL_TIME:
        c = 0
        if q >= 0:
            c = bonds[CLOCK, j] + 1 if bonds[CLOCK, j] > 0 and np.int64(bonds[CAND, j]) == q else 1
        bonds[CAND, j] = q
        bonds[CLOCK, j] = min(c, rules.n_heal + 1)
        ok = ok and c > rules.n_heal
    return ok


# --- Slip weakening (``model.interface``: the peak, the envelope, the secant), chosen by rules.soften --------

# Inlined by numba: the step's kernels and the frames' call it, and a job compiles those on two ranks at
# once (engine.compile); compiled on its own, both would compile it.
@njit(cache=True, inline="always", _nrt=False)
def _forced(p, n, site):
    """The nucleation's share of the weakening of global site ``site`` at step n: (n - n_s)/n_w for n_s <= n <=
    n_s + n_w (1 at n_s when n_w = 0), n_s the step its forcing starts (the nucleation's start, plus the
    forced front's travel from the zone's centre), n_w = nuc_steps; -1 where and when it is not forced."""
    if p.nuc == 0 or site < p.nuc_lo or site >= p.nuc_hi or n < p.nuc_start:
        return -1.0
    t = n - p.nuc_start - np.int64(np.ceil(p.nuc_delay * abs(site + 0.5 - p.nuc_centre)))
    if t < 0 or t > p.nuc_steps:
        return -1.0
    return t / p.nuc_steps if p.nuc_steps > 0 else 1.0


# Inlined by numba: the step's kernels and the frames' call it, and a job compiles those on two ranks at
# once (engine.compile); compiled on its own, both would compile it.
@njit(cache=True, inline="always", _nrt=False)
def _bond_k(p, bonds, j, site, n, s, dy):
    """(k, w): the shear stiffness of top site j's bond (global ``site``) at step n with shear stretch s = x_ij -
    x0 and y_ij = dy, and its weakening share.  Undamaged (peak 0): k_x, 0.  Weakening: the secant
    k = tau_m / (s_p + delta_m) of the envelope tau_m = tau_p - (tau_p - tau_r) w, with delta_m the largest slip
    past the peak (its row, or |s| - s_p if larger), w = min(1, max(delta_m / D_c, the nucleation's share)),
    tau_p = k_x s_p and tau_r = min(mu k_y max(0, delta0 - y_ij), tau_p) (``model.interface``).  Pure: with the
    rows as step n - 1 left them it gives the stiffness step n - 1 applied (at its s, y_ij and n)."""
    kx = bonds[KX, j]
    peak = bonds[PEAK, j]
    zero = like(0, kx)
    if peak == 0:
        return kx, zero
    slipped = max(bonds[SLIPPED, j], abs(s) - peak)
    dc = bonds[SOFTENING, j]
    w = slipped / dc if dc > 0 else zero
    w = min(max(w, like(_forced(p, n, site), kx)), like(1, kx))
    tp = kx * peak
    tr = min(p.mu * max(zero, bonds[KY, j] * (p.delta0 - dy)), tp)
    return (tp - (tp - tr) * w) / (peak + slipped), w


@njit(cache=True, forceinline=True, _nrt=False)
def _shear_k(p, bonds, j, site, n, s, dy):
    """The bond's shear stiffness at step n: k_x without slip weakening (the paper's law, read as such), else
    ``_bond_k``'s."""
    if p.soften:
        return _bond_k(p, bonds, j, site, n, s, dy)[0]
    return bonds[KX, j]


@njit(cache=True, forceinline=True, _nrt=False)
def _soften(p, bonds, j, site, n, dx, dy, dxp, dyp):
    """Step n of top site j's bond (global ``site``; (x_ij, y_ij) = (dx, dy) at u(n), (dxp, dyp) at u(n - 1))
    by the slip-weakening rule: an undamaged bond holds elastically below its breaking length and, unforced,
    breaks at it when D_c = 0 (the paper); at its peak (the length test) or where the nucleation forces it, it
    starts to weaken (peak = |x_ij - x0|, never 0); a weakening bond takes its largest slip past the peak and
    the secant of its envelope (``_bond_k``), and breaks when w = 1 or its length reaches delta_b + D_c.

    Returns (k, holds, spent): the shear stiffness the bond applies this step (or broke with), whether it
    holds, and the energy its weakening took in the step, 1/2 (k_old - k) s(n-1) s(n) (m c^2, float64; k_old
    the stiffness of step n - 1): the staggered energy the stiffness change takes out of the budget, which the
    row ``spent`` sums over the bond's weakening."""
    kx = bonds[KX, j]
    x0 = bonds[X0, j]
    s = dx - x0
    db = bonds[DELTA_B, j]
    dc = bonds[SOFTENING, j]
    forced = _forced(p, n, site)
    l2 = dx * dx + dy * dy
    if bonds[PEAK, j] == 0:
        if forced < 0 and l2 < db * db:
            return kx, True, 0.0
        if forced < 0 and dc == 0:
            return kx, False, 0.0
        bonds[PEAK, j] = max(abs(s), p.tiny)
        bonds[SLIPPED, j] = 0
        bonds[SPENT, j] = 0
        k_old = kx
    else:
        k_old = _bond_k(p, bonds, j, site, n - 1, dxp - x0, dyp)[0]
    bonds[SLIPPED, j] = max(bonds[SLIPPED, j], abs(s) - bonds[PEAK, j])
    k, w = _bond_k(p, bonds, j, site, n, s, dy)
    spent = 0.5 * (float(k_old) - float(k)) * float(dxp - x0) * float(s)
    bonds[SPENT, j] += spent
    lim = db + dc
    return k, w < 1 and l2 < lim * lim, spent


# Inlined by numba: the step's kernels and the frames' call it, and a job compiles those on two ranks at
# once (engine.compile); compiled on its own, both would compile it.
@njit(cache=True, inline="always", _nrt=False)
def _partner(bonds, j):
    """The substrate column site j is bonded to (-1: broken), from its float row."""
    return np.int64(bonds[PARTNER, j])


@njit(cache=True, forceinline=True, _nrt=False)
def _event(it, n, j, site, kind, q, dx, dy, kx, spent):
    """Append one event of top site j (local column; ``site`` global), bond (x_ij, y_ij) = (dx, dy) of shear
    stiffness ``kx``, whose weakening took ``spent`` (m c^2), to the record ``it.events`` (room is guaranteed
    by the caller's agreement)."""
    ev, bonds, k = it.events, it.bonds, it.consts
    c = ev.count[0]
    ev.step[c] = n
    ev.site[c] = site
    ev.kind[c] = kind
    ev.partner[c] = q
    sx = dx - bonds[X0, j]
    sy = dy - it.rules.delta0
    ev.energy[c] = (0.5 * kx * sx * sx + 0.5 * bonds[KY, j] * sy * sy) * k.energy
    ev.traction[c] = kx * sx * k.traction
    ev.dissipated[c] = spent * k.energy
    ev.count[0] = c + 1


@njit(cache=True, _nrt=False)
def update(n, tx, ty, bx, by, tx_prev, ty_prev, bx_prev, by_prev, it, sites):
    """Steps 1-4 above on every local top site at step ``n``, then the bond forces at u(t).

    tx, ty: the block's row 0 at u(t); bx, by: the substrate's interface row; the *_prev: the same at
    u(t - dt), for rules that read the slip velocity and for the budget (``kernels.budget``, pairs by local
    top column in ``sites``' rows): each break of an OWNED site adds the bond's staggered energy
    (``kernels.budget.bond_energy``) to row S_BROKEN, each re-formation to S_FORMED, each step of a weakening
    bond what its weakening took to S_SOFTENED (``_soften``); with a contact, each OWNED site adds the
    staggered energy of its contact spring of this step to S_SWITCHED and takes off that of the step before,
    the same of its stick spring with contact friction, whose slip past the spring adds what friction took
    to S_FRICTION (``_rub``).
    ``partner`` holds global
    bottom columns (-1: broken), indexed by local top column.  Forces go on OWNED top nodes into
    (ext_x, ext_y) and on OWNED bottom nodes into (exb_x, exb_y), both by local column, zero where
    there is no bond.  ``claim`` is scratch: the free sites, then their claims.  Every break and
    re-formation of an OWNED site is counted and appended to ``events`` (``Events``).

    ``reach[0]`` becomes the global column of the first OWNED top site whose bond or re-bonding
    window reaches past this rank's substrate copies (a bond out of reach), else stays -1.
    """
    zero = like(0, it.rules.delta0)
    contact = it.rules.contact > zero
    if contact:                                   # before the breaks: the sites free since the step before
        _contacts_left(tx, ty, bx, by, tx_prev, ty_prev, bx_prev, by_prev, it, sites[bg.S_SWITCHED])
    _clear(it, zero)
    nfree = _breaks(n, tx, ty, bx, by, tx_prev, ty_prev, bx_prev, by_prev, it, zero, sites[bg.S_BROKEN],
                    sites[bg.S_SOFTENED])
    _claims(nfree, tx, ty, bx, by, tx_prev, bx_prev, it, zero)
    _grants(n, nfree, tx, ty, bx, by, tx_prev, ty_prev, bx_prev, by_prev, it, zero, sites[bg.S_FORMED])
    if contact:
        _contacts(nfree, tx, ty, bx, by, tx_prev, ty_prev, bx_prev, by_prev, it, sites[bg.S_SWITCHED],
                  sites[bg.S_FRICTION])


@njit(cache=True, _nrt=False)
def _clear(it, zero):
    """No substrate site taken yet; no force on the OWNED bottom sites yet."""
    g = it.geom
    for i in range(g.blo, g.bhi):
        it.taken[i] = 0
    for i in range(g.bown0, g.bown1):
        it.exb_x[i] = zero
        it.exb_y[i] = zero


@njit(cache=True, _nrt=False)
def _breaks(n, tx, ty, bx, by, txp, typ, bxp, byp, it, zero, broken, softened):
    """1. Breaks (by the length test, or with slip weakening by ``_soften``); the bonds that hold mark their
    substrate site taken and apply their force now (the positions do not change within the step).  The
    free sites are listed in ``claim``; returns how many."""
    g, p, bonds, reach = it.geom, it.rules, it.bonds, it.reach
    tbase, bbase, d0 = g.tbase, g.bbase, p.delta0
    site0 = tbase - g.tfirst                          # global site = local column + site0
    nfree = 0
    for j in range(g.tlo, g.thi):
        q = _partner(bonds, j)
        top_own = g.town0 <= j < g.town1
        if top_own:
            it.ext_x[j] = zero
            it.ext_y[j] = zero
        if q >= 0:
            i = q - bbase
            if i < g.blo or i >= g.bhi:
                if top_own and reach[0] < 0:
                    reach[0] = j + tbase
                continue
            dx, dy = _gap(j + tbase, q, tx, ty, bx, by, j, i, d0)
            kx = bonds[KX, j]
            if p.soften:
                dxp, dyp = _gap(j + tbase, q, txp, typ, bxp, byp, j, i, d0)
                kx, holds, spent = _soften(p, bonds, j, j + site0, n, dx, dy, dxp, dyp)
                if top_own and spent != 0:
                    bg.add(softened, j, spent)
            else:
                db = bonds[DELTA_B, j]
                holds = dx * dx + dy * dy < db * db
            if holds:
                it.taken[i] = 1
                _apply(j, i, dx, dy, kx, bonds, top_own, g.bown0, g.bown1, d0, it.ext_x, it.ext_y, it.exb_x,
                       it.exb_y)
                continue
            if top_own:
                it.counters[BREAKS] += 1
                _event(it, n, j, j + site0, BREAK, q, dx, dy, kx, bonds[SPENT, j] if p.soften else zero)
                bg.add(broken, j, _staggered_bond(j + tbase, q, tx, ty, bx, by, txp, typ, bxp, byp, j, i, d0, bonds,
                                                  kx))
            if p.mu > zero:                # friction takes over the bond's shear force (``_contacts`` bounds it)
                bonds[STICK, j] = kx * (dx - bonds[X0, j]) / p.contact
            bonds[PARTNER, j] = -1
        it.claim[nfree] = j
        nfree += 1
    return nfree


@njit(cache=True, forceinline=True, _nrt=False)
def _dx(gl, q, txj, bx, bbase, d0):
    """x_ij of top site ``gl`` (x-displacement ``txj``) and substrate column q, as ``_gap`` computes it."""
    return like(gl - q, d0) + (txj - bx[q - bbase])


@njit(cache=True, _nrt=False)
def _span(gl, txj, bx, g, r, d0):
    """The substrate columns [lo, hi] whose sites are within ``r`` in x of top site ``gl`` now
    (|x_ij| <= r), and whether the walk met the end of this rank's copies where the row goes on.

    Starts at the column the top site is nearest to, moved by the drift of the substrate site found
    there, and walks: the substrate's interface row is in x order (the loop checks it), so x_ij falls
    with q and the sites within r are one run of columns.  None within r: a one-column span whose site
    is beyond r (the caller's distance test rejects it); no substrate copies at all: an empty span."""
    bbase = g.bbase
    qmin = max(g.blo + bbase, 0)
    qmax = min(g.bhi + bbase, g.bcols) - 1
    if qmax < qmin:
        return qmin, qmin - 1, False
    q = min(max(np.int64(np.floor(like(gl, d0) + txj + 0.5)), qmin), qmax)
    q = min(max(q - np.int64(np.floor(bx[q - bbase] + 0.5)), qmin), qmax)
    while q < qmax and _dx(gl, q, txj, bx, bbase, d0) > r:
        q += 1
    while q > qmin and _dx(gl, q, txj, bx, bbase, d0) < -r:
        q -= 1
    lo = hi = q
    while lo > qmin and _dx(gl, lo - 1, txj, bx, bbase, d0) <= r:
        lo -= 1
    while hi < qmax and _dx(gl, hi + 1, txj, bx, bbase, d0) >= -r:
        hi += 1
    return lo, hi, (lo == qmin and qmin > 0) or (hi == qmax and qmax < g.bcols - 1)


@njit(cache=True, _nrt=False)
def _claims(nfree, tx, ty, bx, by, tx_prev, bx_prev, it, zero):
    """2. Each free site's claim: the nearest untaken substrate site within the re-bond length R (REBOND_FACING:
    only the one nearest in x), if the healing rule lets it; kept with its site in its slot m of ``claim``
    (site and claim in one integer).  The sites are looked for within R + SEARCH_MARGIN in x (``_span``)."""
    g, p, bonds, claim, reach = it.geom, it.rules, it.bonds, it.claim, it.reach
    tbase, bbase, thi, d0 = g.tbase, g.bbase, g.thi, p.delta0
    d02 = p.rebond_length * p.rebond_length
    r = p.rebond_length + like(SEARCH_MARGIN, d0)
    for m in range(nfree):
        j = claim[m]
        gl = j + tbase
        lo, hi, cut = _span(gl, tx[j], bx, g, r, d0)
        if cut and g.town0 <= j < g.town1 and reach[0] < 0:
            reach[0] = gl
        if p.rebond == REBOND_FACING and hi > lo:
            near = lo
            for q in range(lo + 1, hi + 1):
                if abs(_dx(gl, q, tx[j], bx, bbase, d0)) < abs(_dx(gl, near, tx[j], bx, bbase, d0)):
                    near = q
            lo = hi = near
        best = np.inf
        got = -1
        for q in range(lo, hi + 1):
            i = q - bbase
            if it.taken[i]:
                continue
            dx, dy = _gap(gl, q, tx, ty, bx, by, j, i, d0)
            d2 = dx * dx + dy * dy
            if d2 <= d02 and d2 < best:
                best = d2
                got = i
        if p.heal and not _heals(p, bonds, j, got + bbase if got >= 0 else -1,
                                 (tx[j] - tx_prev[j]) - (bx[got] - bx_prev[got]) if got >= 0 else zero):
            got = -1
        claim[m] = got * (thi + 1) + j if got >= 0 else -1 - j


@njit(cache=True, _nrt=False)
def _grants(n, nfree, tx, ty, bx, by, txp, typ, bxp, byp, it, zero, formed):
    """3. Grants in increasing site order (the free list is in site order); a new bond's force applies at once."""
    g, p, bonds = it.geom, it.rules, it.bonds
    tbase, bbase, thi, d0 = g.tbase, g.bbase, g.thi, p.delta0
    site0 = tbase - g.tfirst
    for m in range(nfree):
        c = it.claim[m]
        if c < 0:
            continue
        i, j = c // (thi + 1), c % (thi + 1)
        if it.taken[i]:
            continue
        it.taken[i] = 1
        bonds[PARTNER, j] = i + bbase
        dx, dy = _gap(j + tbase, i + bbase, tx, ty, bx, by, j, i, d0)
        bonds[X0, j] = _rest_offset(p.reform, dx, zero)
        bonds[CLOCK, j] = 0
        if p.soften:                                   # a re-formed bond starts undamaged
            bonds[PEAK, j] = zero
            bonds[SLIPPED, j] = zero
            bonds[SPENT, j] = zero
        bonds[STICK, j] = zero                         # and its site has no contact
        kx = bonds[KX, j]
        top_own = g.town0 <= j < g.town1
        _apply(j, i, dx, dy, kx, bonds, top_own, g.bown0, g.bown1, d0, it.ext_x, it.ext_y, it.exb_x, it.exb_y)
        if top_own:
            it.counters[FORMS] += 1
            _event(it, n, j, j + site0, FORM, i + bbase, dx, dy, kx, zero)
            bg.add(formed, j, _staggered_bond(j + tbase, i + bbase, tx, ty, bx, by, txp, typ, bxp, byp, j, i, d0,
                                              bonds, kx))


# What ``_surface`` returns for a site with no surface under it (beyond the substrate's ends), and for one
# whose segment is not stored on this rank (out of the halo's reach).
NO_SURFACE, FAR = -1, -2


# Inlined by numba: the step's kernels and the frames' call it, and a job compiles those on two ranks at
# once (engine.compile); compiled on its own, both would compile it.
@njit(cache=True, inline="always", _nrt=False)
def _surface(gl, j, tx, ty, bx, by, g, d0):
    """The substrate's surface under top site j (global column ``gl``) at the positions given
    (``model.interface``): (i, nx, ny, w, d), i the local column of the segment's first substrate site (the
    pair that brackets the site's x, as the sites have drifted), (nx, ny) its upward unit normal, w the
    site's weight along it (clipped to [0, 1]) and d the site's height above it (a); i = NO_SURFACE beyond
    the substrate's ends, FAR where the segment is not stored here."""
    one = like(1, d0)
    nil = 0 * one
    x = like(gl, d0) + tx[j]                              # the site's x, in substrate columns
    q = np.int64(np.floor(x))
    if q < 0 or q + 1 >= g.bcols:
        return NO_SURFACE, nil, nil, nil, nil             # beyond the substrate's ends: no surface
    i = q - g.bbase
    if i - 1 < g.blo or i + 2 > g.bhi:
        return FAR, nil, nil, nil, nil
    if x < q + bx[i]:                                     # the bracketing pair, as the sites have drifted
        i -= 1
    elif x >= q + 1 + bx[i + 1]:
        i += 1
    ex, ey = one + (bx[i + 1] - bx[i]), by[i + 1] - by[i]
    rx, ry = like(gl - (i + g.bbase), d0) + (tx[j] - bx[i]), d0 + (ty[j] - by[i])
    ln = np.sqrt(ex * ex + ey * ey)
    nx, ny = -ey / ln, ex / ln
    d = rx * nx + ry * ny
    w = min(max((rx * ex + ry * ey) / (ln * ln), nil), one)
    return i, nx, ny, w, d


# Inlined by numba: the step's kernels and the frames' call it, and a job compiles those on two ranks at
# once (engine.compile); compiled on its own, both would compile it.
@njit(cache=True, inline="always", _nrt=False)
def _offset(gl, j, i, w, tx, ty, bx, by, bbase, d0):
    """r - w e (a, float64): from the point at weight w along the segment of substrate sites (i, i + 1) to top
    site j (global column ``gl``), at the positions given; affine in the three nodes' displacements."""
    rx = float(gl - (i + bbase)) + (float(tx[j]) - float(bx[i]))
    ry = float(d0) + (float(ty[j]) - float(by[i]))
    ex = 1.0 + (float(bx[i + 1]) - float(bx[i]))
    ey = float(by[i + 1]) - float(by[i])
    w = float(w)
    return rx - w * ex, ry - w * ey


# Inlined by numba: the step's kernels and the frames' call it, and a job compiles those on two ranks at
# once (engine.compile); compiled on its own, both would compile it.
@njit(cache=True, inline="always", _nrt=False)
def _compression(gl, j, i, nx, ny, w, tx, ty, bx, by, bbase, d0):
    """The compression delta0 - n . (r - w e) (a, float64) of the contact spring (i, n, w) of top site j at the
    positions given: affine in the three nodes' displacements, delta0 - d where the spring was set up."""
    ox, oy = _offset(gl, j, i, w, tx, ty, bx, by, bbase, d0)
    return float(d0) - (float(nx) * ox + float(ny) * oy)


# Inlined by numba: the step's kernels and the frames' call it, and a job compiles those on two ranks at
# once (engine.compile); compiled on its own, both would compile it.
@njit(cache=True, inline="always", _nrt=False)
def _along(gl, j, i, nx, ny, w, tx, ty, bx, by, bbase, d0):
    """xi = t . (r - w e) (a, float64), t = (n_y, -n_x) the segment's unit tangent: top site j's place along the
    surface of the contact spring (i, n, w) at the positions given, affine in the three nodes' displacements."""
    ox, oy = _offset(gl, j, i, w, tx, ty, bx, by, bbase, d0)
    return float(ny) * ox - float(nx) * oy


# Inlined by numba: the step's kernels and the frames' call it, and a job compiles those on two ranks at
# once (engine.compile); compiled on its own, both would compile it.
@njit(cache=True, inline="always", _nrt=False)
def _stick(e_prev, gl, j, i, nx, ny, w, d, tx, ty, bx, by, txp, typ, bxp, byp, bbase, d0, mu):
    """Contact friction (``model.interface``): the stick spring's stretch e = clip(e_prev + dxi, -c, c) (a,
    float64) after the site's slip dxi = xi(u(n)) - xi(u(n-1)) along this step's surface (i, n, w, ``_along``),
    c = mu (delta0 - d), where the spring's force k_c e reaches mu times the normal force k_c (delta0 - d).
    Returns (e, dxi).  Pure: the rule ``_contacts`` applies, and what ``record`` reads."""
    dxi = (_along(gl, j, i, nx, ny, w, tx, ty, bx, by, bbase, d0)
           - _along(gl, j, i, nx, ny, w, txp, typ, bxp, byp, bbase, d0))
    cap = float(mu) * (float(d0) - float(d))
    return min(max(float(e_prev) + dxi, -cap), cap), dxi


# Inlined by numba: the step's kernels and the frames' call it, and a job compiles those on two ranks at
# once (engine.compile); compiled on its own, both would compile it.
@njit(cache=True, inline="always", _nrt=False)
def _contact_before(j, tx, ty, bx, by, txp, typ, bxp, byp, it):
    """(normal, tangential): the staggered energies (``kernels.budget.contact_energy``) at (u(n-1), u(n)) of the
    contact spring and of the stick spring free site j had in the step before, set up from u(n-1) (the *p
    arrays; the stick's stretch as the row holds it, e(n-1)); 0 where it had none."""
    g, p = it.geom, it.rules
    d0 = p.delta0
    gl = j + g.tbase
    i, nx, ny, w, d = _surface(gl, j, txp, typ, bxp, byp, g, d0)
    if i < 0 or d >= d0:
        return 0.0, 0.0
    normal = bg.contact_energy(p.contact, d0 - d, _compression(gl, j, i, nx, ny, w, tx, ty, bx, by, g.bbase, d0))
    e = float(it.bonds[STICK, j])
    if e == 0.0:
        return normal, 0.0
    moved = (_along(gl, j, i, nx, ny, w, tx, ty, bx, by, g.bbase, d0)
             - _along(gl, j, i, nx, ny, w, txp, typ, bxp, byp, g.bbase, d0))
    return normal, bg.contact_energy(p.contact, e, e + moved)


@njit(cache=True, _nrt=False)
def _contacts_left(tx, ty, bx, by, txp, typ, bxp, byp, it, switched):
    """Each OWNED site free since the step before (partner -1 before the breaks) takes the staggered energy of
    its contact spring and its stick spring of that step off ``switched``: this step replaces both springs
    (``_contacts``)."""
    g, bonds = it.geom, it.bonds
    for j in range(g.town0, g.town1):
        if _partner(bonds, j) < 0:
            e, t = _contact_before(j, tx, ty, bx, by, txp, typ, bxp, byp, it)
            if e + t != 0.0:
                bg.add(switched, j, -(e + t))


@njit(cache=True, _nrt=False)
def _contacts(nfree, tx, ty, bx, by, txp, typ, bxp, byp, it, switched, rubbed):
    """4. Contact: each site still free after the grants, in increasing site order, is pushed off the
    substrate's surface (``_surface``) by f = k_c (delta0 - d) along the segment's normal when its distance
    d is below delta0; the opposite force goes to the segment's ends by the interpolation weights (1 - w,
    w).  A substrate site gathers the contacts of the sites around it in site order, after its bond's force.
    Each OWNED site in contact adds its spring's staggered energy at (u(n-1), u(n)) to ``switched``.  With
    contact friction (``_rub``) its stick spring acts along the surface too; a free site out of contact has
    no stick."""
    g, p, claim, reach = it.geom, it.rules, it.claim, it.reach
    tbase, thi, d0, kc = g.tbase, g.thi, p.delta0, p.contact
    one = like(1, d0)
    for m in range(nfree):
        c = claim[m]
        j = -1 - c if c < 0 else c % (thi + 1)
        if _partner(it.bonds, j) >= 0:
            continue
        gl = j + tbase
        own = g.town0 <= j < g.town1
        i, nx, ny, w, d = _surface(gl, j, tx, ty, bx, by, g, d0)
        if i == FAR and own and reach[0] < 0:
            reach[0] = gl
        if i < 0 or d >= d0:
            it.bonds[STICK, j] = 0 * one
            continue
        f = kc * (d0 - d)
        if own:
            it.ext_x[j] = f * nx
            it.ext_y[j] = f * ny
            bg.add(switched, j, bg.contact_energy(kc, _compression(gl, j, i, nx, ny, w, txp, typ, bxp, byp, g.bbase,
                                                                   d0), d0 - d))
        if g.bown0 <= i < g.bown1:
            it.exb_x[i] -= (one - w) * f * nx
            it.exb_y[i] -= (one - w) * f * ny
        if g.bown0 <= i + 1 < g.bown1:
            it.exb_x[i + 1] -= w * f * nx
            it.exb_y[i + 1] -= w * f * ny
        if p.mu > 0 * one:
            _rub(gl, j, i, nx, ny, w, d, tx, ty, bx, by, txp, typ, bxp, byp, it, own, switched, rubbed)


@njit(cache=True, forceinline=True, _nrt=False)
def _rub(gl, j, i, nx, ny, w, d, tx, ty, bx, by, txp, typ, bxp, byp, it, own, switched, rubbed):
    """Contact friction on free site j in contact with the segment (i, n, w) at height d: its stick spring's
    new stretch e(n) (``_stick``) into the row, its force -k_c e(n) t on the top node and -(1 - w), -w of it on
    the segment's ends (OWNED ones).  For an OWNED site: friction took k_c p (e(n-1) + e(n))/2, p = e(n-1) +
    dxi - e(n) the slip past the spring (``rubbed``; at a hand-over from a bond, e(n-1) is the bond's stretch
    the row was given), and the spring's staggered energy at (u(n-1), u(n)) appears with it (``switched``:
    the energy plus what friction took, so that ``switched`` less ``rubbed`` is what the springs' switches
    changed; ``_contacts_left`` takes the spring off when the next step replaces it)."""
    g, p, bonds = it.geom, it.rules, it.bonds
    one = like(1, p.delta0)
    before = float(bonds[STICK, j])
    e, dxi = _stick(bonds[STICK, j], gl, j, i, nx, ny, w, d, tx, ty, bx, by, txp, typ, bxp, byp, g.bbase,
                    p.delta0, p.mu)
    bonds[STICK, j] = e
    ft = -p.contact * bonds[STICK, j]                      # along t = (n_y, -n_x), with the stretch the row holds
    fx, fy = ft * ny, -ft * nx
    if own:
        it.ext_x[j] += fx
        it.ext_y[j] += fy
        es = float(bonds[STICK, j])
        took = 0.5 * float(p.contact) * (before + dxi - es) * (before + es)
        bg.add(rubbed, j, took)
        bg.add(switched, j, bg.contact_energy(p.contact, es - dxi, es) + took)
    if g.bown0 <= i < g.bown1:
        it.exb_x[i] -= (one - w) * fx
        it.exb_y[i] -= (one - w) * fy
    if g.bown0 <= i + 1 < g.bown1:
        it.exb_x[i + 1] -= w * fx
        it.exb_y[i + 1] -= w * fy


@njit(cache=True, forceinline=True, _nrt=False)
def _rubbing(gl, j, tx, ty, bx, by, txp, typ, bxp, byp, it):
    """The x-force (m c^2/a) contact friction puts on free top site j in step n (``_rub``'s, the row left as it
    is): 0 without friction or out of contact."""
    g, p = it.geom, it.rules
    d0 = p.delta0
    if p.mu == 0 * d0:
        return 0.0
    i, nx, ny, w, d = _surface(gl, j, tx, ty, bx, by, g, d0)
    if i < 0 or d >= d0:
        return 0.0
    e, _ = _stick(it.bonds[STICK, j], gl, j, i, nx, ny, w, d, tx, ty, bx, by, txp, typ, bxp, byp, g.bbase, d0, p.mu)
    return float(-p.contact * like(e, d0) * ny)


@njit(cache=True, forceinline=True, _nrt=False)
def _apply(j, i, dx, dy, kx, bonds, top_own, bown0, bown1, d0, ext_x, ext_y, exb_x, exb_y):
    """The bond's force f_x = -k_x (x_ij - x0), f_y = -k_y (y_ij - delta0) on its OWNED ends (k_x the bond's
    shear stiffness this step, ``_shear_k``; k_y the top site's own)."""
    bot_own = bown0 <= i < bown1
    if top_own or bot_own:
        fx = -kx * (dx - bonds[X0, j])
        fy = -bonds[KY, j] * (dy - d0)
        if top_own:
            ext_x[j] = fx
            ext_y[j] = fy
        if bot_own:
            exb_x[i] = -fx
            exb_y[i] = -fy


@njit(cache=True, _nrt=False)
def coverage(tx, bx, g):
    """True when this rank's interface copies reach far enough in the current positions (``layout.Reach``).

    The region of interest is the current x of this rank's own substrate sites and of its own top sites;
    the block's interface row must be stored over it plus ``top_cover`` a, and the substrate's over it
    plus ``bottom_cover`` a, both in current x, except where a row ends.  Both rows stay in x order.
    """
    tbase, tlo, thi, town0, town1 = g.tbase, g.tlo, g.thi, g.town0, g.town1
    bbase, blo, bhi, bown0, bown1 = g.bbase, g.blo, g.bhi, g.bown0, g.bown1
    if thi <= tlo:
        return True
    have = False
    lo = 0.0
    hi = 0.0
    if bown1 > bown0:
        lo, hi, have = bown0 + bbase + float(bx[bown0]), bown1 - 1 + bbase + float(bx[bown1 - 1]), True
    if town1 > town0:
        a = town0 + tbase + float(tx[town0])
        b = town1 - 1 + tbase + float(tx[town1 - 1])
        lo, hi = (min(lo, a), max(hi, b)) if have else (a, b)
        have = True
    if not have:
        return True
    ct, cb = g.tcover, g.bcover
    if tlo + tbase > g.tfirst and tlo + tbase + float(tx[tlo]) > lo - ct:
        return False
    if thi - 1 + tbase < g.tlast and thi - 1 + tbase + float(tx[thi - 1]) < hi + ct:
        return False
    if blo + bbase > 0 and blo + bbase + float(bx[blo]) > lo - cb:
        return False
    if bhi - 1 + bbase < g.bcols - 1 and bhi - 1 + bbase + float(bx[bhi - 1]) < hi + cb:
        return False
    return True


# Inlined by numba: the step's kernels and the frames' call it, and a job compiles those on two ranks at
# once (engine.compile); compiled on its own, both would compile it.
@njit(cache=True, inline="always", _nrt=False)
def _staggered_bond(g, q, tx, ty, bx, by, txp, typ, bxp, byp, j, i, d0, bonds, kx):
    """The staggered energy of top site j's bond to substrate site i (global g, q) between u(n-1) and u(n),
    with shear stiffness ``kx``."""
    dx1, dy1 = _gap(g, q, tx, ty, bx, by, j, i, d0)
    dx0, dy0 = _gap(g, q, txp, typ, bxp, byp, j, i, d0)
    x0 = bonds[X0, j]
    return bg.bond_energy(kx, bonds[KY, j], dx0 - x0, dy0 - d0, dx1 - x0, dy1 - d0)


@njit(cache=True, _nrt=False)
def staggered(n, tx, ty, bx, by, txp, typ, bxp, byp, it, out):
    """out[ELASTIC] += the staggered energy of every intact bond of the OWNED top sites (``kernels.budget``),
    with the bonds as they stand before step n's update (a weakening bond with the stiffness step n - 1 gave
    it, ``_shear_k`` at u(n - 1))."""
    g, bonds, p = it.geom, it.bonds, it.rules
    d0 = p.delta0
    for j in range(g.town0, g.town1):
        q = _partner(bonds, j)
        i = q - g.bbase
        if q >= 0 and g.blo <= i < g.bhi:
            gl = j + g.tbase
            dxp, dyp = _gap(gl, q, txp, typ, bxp, byp, j, i, d0)
            kx = _shear_k(p, bonds, j, gl - g.tfirst, n - 1, dxp - bonds[X0, j], dyp)
            bg.add(out, bg.ELASTIC, _staggered_bond(gl, q, tx, ty, bx, by, txp, typ, bxp, byp, j, i, d0, bonds, kx))


@njit(cache=True, _nrt=False)
def contact_staggered(tx, ty, bx, by, txp, typ, bxp, byp, it, out):
    """out[CONTACT] += the staggered energy of the contact spring and the stick spring of every OWNED free top
    site (``kernels.budget``), the springs of the step before (set up from u(n-1), the *p arrays)."""
    g, bonds = it.geom, it.bonds
    for j in range(g.town0, g.town1):
        if _partner(bonds, j) < 0:
            normal, tangential = _contact_before(j, tx, ty, bx, by, txp, typ, bxp, byp, it)
            bg.add(out, bg.CONTACT, normal + tangential)


@njit(cache=True, _nrt=False)
def shear_sum(n, tx, ty, bx, by, txp, typ, bxp, byp, it, lo, hi, quantum):
    """The shear force (m c^2/a: the frames' sxy times a rho c_r^2) this rank's OWNED sites of global index in
    [lo, hi) carry at u(n), a bond's k (x_ij - x0) or a free site's contact friction (``_rubbing``; the *p
    arrays are u(n - 1)), each rounded to a whole number of ``quantum`` and summed as an integer: exact, so
    the ranks' sums add to the same value in any order (``engine.prestress``)."""
    g, bonds, p = it.geom, it.bonds, it.rules
    total = 0
    for j in range(g.town0, g.town1):
        site = j + g.tbase - g.tfirst
        if not lo <= site < hi:
            continue
        q = _partner(bonds, j)
        i = q - g.bbase
        f = 0.0
        if q >= 0 and g.blo <= i < g.bhi:
            dx, dy = _gap(j + g.tbase, q, tx, ty, bx, by, j, i, p.delta0)
            s = dx - bonds[X0, j]
            f = float(_shear_k(p, bonds, j, site, n, s, dy) * s)
        elif q < 0:
            f = -_rubbing(j + g.tbase, j, tx, ty, bx, by, txp, typ, bxp, byp, it)
        total += np.int64(np.floor(f / quantum + 0.5))
    return total


@njit(cache=True, _nrt=False)
def record(n, tx, ty, bx, by, txp, typ, bxp, byp, it, k, fr):
    """Frame k (at step n; the *p arrays u(n - 1)) of the interface record for the OWNED top sites into the
    buffer ``fr`` (``loop.Frames``): intact, partner, u/l, the traction sxy = k_x (x_ij - x0) / (a rho c_r^2) =
    -f_x/(a rho c_r^2), syy = k_y (y_ij - delta0)/(a rho c_r^2), and the bond's x-force on the block f_x = -k_x
    (x_ij - x0) (m c^2/a), which the writer sums over the sites into the friction force; k_x is the stiffness
    the bond has at u(n) (a weakening bond's secant, ``_shear_k``).  Where broken, f_x and sxy are those of
    the contact's friction in step n (``_rubbing``: 0 without it), and syy is 0 (the contact's normal force
    is not recorded)."""
    g, p, bonds, rules = it.geom, it.consts, it.bonds, it.rules
    tbase, town0, town1 = g.tbase, g.town0, g.town1
    bbase, blo, bhi = g.bbase, g.blo, g.bhi
    d0, inv_l, tr = it.rules.delta0, p.inv_l, p.traction
    for m in range(town1 - town0):
        j = town0 + m
        q = _partner(bonds, j)
        fr.partner[k, m] = q
        fr.intact[k, m] = 1 if q >= 0 else 0
        fr.ux[k, m] = tx[j] * inv_l
        fr.uy[k, m] = ty[j] * inv_l
        i = q - bbase
        if q >= 0 and blo <= i < bhi:
            dx, dy = _gap(j + tbase, q, tx, ty, bx, by, j, i, d0)
            s = dx - bonds[X0, j]
            sx = _shear_k(rules, bonds, j, j + tbase - g.tfirst, n, s, dy) * s
            fr.sxy[k, m] = sx * tr
            fr.syy[k, m] = bonds[KY, j] * (dy - d0) * tr
            fr.fx[k, m] = -sx
        else:
            fr.sxy[k, m] = 0.0
            fr.syy[k, m] = 0.0
            fr.fx[k, m] = 0.0
            if q < 0 and rules.mu > 0:
                fx = _rubbing(j + tbase, j, tx, ty, bx, by, txp, typ, bxp, byp, it)
                fr.sxy[k, m] = -fx * tr
                fr.fx[k, m] = fx
