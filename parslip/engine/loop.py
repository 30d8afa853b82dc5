"""The compiled time loop: many Verlet steps per call, between which Python agrees, writes and checks.

Responsible for the order of one step and the load phases (ramp F_N, settle
with damping, drive), and for stopping where Python must act: the end of the
requested steps, a full buffer of interface frames, or a problem (a state
that is not finite or grows without bound, a bond out of the halo's reach, a
substrate interface row that folded: a site passed its neighbour in x).

One step n -> n+1, at positions u(n) (level n % 2; level (n+1) % 2 holds
u(n-1) and receives u(n+1)):

 1. record interface frame k if n is its step (u(n), bonds as they entered);
 2. interface bonds: break, re-form, forces (``kernels.interface``), on every
    local interface site, OWNED and HALO; check that the halo still covers them;
 3. the schedule's EARLY tasks: the rows and columns peers keep as HALO;
 4. ``post``: send them with the bond state, post the receives;
 5. the LATE tasks, while messages travel (``progress`` halfway);
 6. ``complete``: HALO copies now hold u(n+1) and the bonds of step n.

A driven node is first updated like any other; the drive then sets its x to
the prescribed value and keeps the force that took (``drive_force``) in the
steps whose end someone reads: a frame's step, or the end of the call.

The rule for collective decisions.  Everything after which a rank enters an
MPI collective (a write of frames, events or a snapshot, a checkpoint, a
stop) must happen at the same step on every rank.  So ``advance`` returns
only where every rank returns:
  - at ``n1``, which the caller computes from data every rank holds (the
    agreed chunk, the snapshot steps, the checkpoint steps);
  - FRAMES_FULL, when the frame buffer is full: its capacity is the same on
    every rank (sized from the largest slab's site count, ``Simulation``),
    and frames are recorded at the same steps everywhere;
  - STOPPED, when the flags, agreed every ``check_every`` steps with one
    ``reduce_max``, say some rank found a problem;
  - EVENTS_FULL, when the same agreement says some rank holds more than
    ``event_limit`` bond events: the record is sized so that it cannot
    overflow before the next agreement (2 events per OWNED site per step).
The exchange plan is passed in: on one rank it is a ``NullPlan`` and every
exchange phase is a no-op that links no MPI (``parallel.exchange``).

Parameters travel as named tuples (``Params``, ``Schedule``, ``Iface``,
``Frames``, ``Diag``), never as numbered slots; the few int arrays that must
be arrays (flags reduced over MPI, timers, the frame cursor, the heartbeat)
are indexed by the named constants below.
"""
from collections import namedtuple

import numpy as np
from numba import njit

from ..model.drive import DRIVE_SPRING, DRIVE_X, DRIVE_XY  # noqa: F401  (the drive word's bits, ``model.drive``)
from ..parallel.exchange import complete, post, progress, reduce_max
from ..parallel.plans import REDUCE_WORDS
from ..parallel.codes import ALL_BONDS, EARLY, END, FULL, LATE, MASKED, NO_DOWN, NO_UP, NODES, PAD, ROWS
from .kernels import budget as bg
from .kernels import interface as ik
from .kernels.clock import now_ns
from .kernels.floats import like
from .kernels.scheme import ramp_share
from .kernels.rect import rect_full
from .kernels.stencil import K_RATE, budget_shares, masked_force, node_masked, rate_field, row_edge

# State: each block as [row, column] arrays, x and y apart, at two Verlet levels; and the field z whose bond
# forces the update takes with the bonds' damping (``kernels.stencil.rate_field``; 1 x 1 arrays without it).
Levels = namedtuple("Levels", "bx0 by0 bx1 by1 tx0 ty0 tx1 ty1 zbx zby ztx zty")
# One level: (bx, by, tx, ty).
Level = namedtuple("Level", "bx by tx ty")
# The row schedule (``parallel.layout``): tasks of TASK_DTYPE and ptr[phase, block, ROWS | NODES | END].
Schedule = namedtuple("Schedule", "tasks ptr")
# The drive: drive0, the x of the top block's nodes when the drive started; index[prow, j] the slot of a
# driven node in ``force`` (-1 not driven); force, the x-force the drive applied to each in the last step.
Drive = namedtuple("Drive", "drive0 index force")
# Interface frame buffer: ``cap`` frames of the OWNED top sites (``kernels.interface.record``), the drive
# force of each OWNED driven node, the step of each frame, and the cursor [C_BASE, C_COUNT, C_LAST].
Frames = namedtuple("Frames", "intact partner ux uy sxy syy fx fdrive energy step cursor")
# The energy budget on one rank (``kernels.budget``): acc [N_Q, 2] int64, the exact sums the row kernels
# make (``kernels.exact``: the damping since the drive started; the kinetic and bulk elastic energy of the
# last step that ended on a frame); work per driven slot, an array [2, slots] of float pairs (hi, lo); sites
# [row, 2, site], the running totals per interface site (local column of the block's interface row), one row
# of pairs per term of ``kernels.budget.SITE_TERMS`` (broken, formed, the contacts' switches, the weakening,
# friction);
# base [2, N_TERMS]:
# what a restart carried over (rank 0); prev [2, slots]: each driven slot's u(n-1) (x, y); scale [N_Q]: each
# exact sum's quanta per m c^2 (``kernels.exact.scales``); cs: the kernels' factors with them,
# [zeta/(4 dt) S_damp, -S_damp/(2 C), S_kin/(2 dt^2), -S_el/(2 C)] (``stencil.budget_shares``).
Budget = namedtuple("Budget", "acc work sites base prev cs scale")
# What the loop reports: flags (this rank's first problem, and its interface rows' drift), gflags (their MAX over
# the ranks), timers (ns per phase), beat (BEAT_STEP: the step the loop last passed, read by the monitor
# thread), halo (the drift box the halos were built for, and the drift at the last agreement: ``H_*``).
Diag = namedtuple("Diag", "flags gflags timers beat halo")
# Scalars of one run (``Simulation.params``):
#   n_ramp, n_drive_start   steps of the F_N ramp, and the first drive step
#   drive                   0 no drive; DRIVE_X the driven face's x is prescribed; DRIVE_XY its y is also
#                           held where it was when the drive started (``drive.hold = "xy"``); DRIVE_SPRING
#                           or'ed in: the face is tied to a loader by springs instead (``drive.spring``)
#   frame_every, n_frames   interface frame cadence (steps) and frames in this run
#   frame_offset            index in the file of this run's frame 0 (a restart may change the cadence)
#   check_every             steps between checks and agreements of the flags
#   has_iface, rigid        an interface exists; the substrate is rigid
#   brow                    array row of the substrate's interface row
#   dt, v0, fext, jump      time step (a/c), drive speed (a c/a), load per node at full F_N, runaway limit (a)
#   cf, inv_cf, damped      C = dt^2/(1 + zeta dt/2) in the state's float type, 1/C, zeta > 0
#   rated                   the bonds' damping: bond forces are taken on z = u + g (u - u_prev) (``K_RATE``)
#   drag                    the kernels sum the body drag's dissipation every step (``output.energy = "checked"``)
#   event_limit             events a rank may hold at an agreement before every rank returns EVENTS_FULL
#   spring, v0dt            the loader spring k_s (m c^2/a^2, with DRIVE_SPRING) and v0 dt (a), in the float type
#   follow, shift           the halos follow the interface's drift (several ranks, no explicit slip reach): the
#                           agreements also reduce the drift and return REBUILD when it nears the halo's box;
#                           shift D: the block's columns stand at x-columns c + D (``parallel.layout.Drift``)
#   n_hold                  the step from which the loader holds still (``drive.prestress``: set by ``Simulation``
#                           once the interface's mean shear traction has reached tau_0; NEVER until then)
Params = namedtuple("Params", "n_ramp n_drive_start drive frame_every n_frames frame_offset check_every has_iface "
                              "rigid brow dt v0 fext jump cf inv_cf damped event_limit spring v0dt rated drag follow "
                              "shift n_hold")

# Or'ed into the step's drive mode when the drive's force must be kept: in a step that ends on an interface
# frame (the frame records it) or on the end of the call (a checkpoint or a restart may read it there).
# Other steps skip it: a store per driven node, 3 % of a small shear step.
KEEP_FORCE = 4

# Frame cursor: [first frame index held in the buffer, frames held, last frame index recorded].
C_BASE, C_COUNT, C_LAST = range(3)

# Flags: [status bits, step, block, row, global column, value*1e6 as int, events held, then the drift of this
# rank's interface rows in DRIFT_QUANTA per a, outward: the largest u_x - D of its block's interface sites,
# the largest -(u_x - D), the largest u_x of its substrate's interface sites, the largest -u_x].  The MAX over
# the ranks of L_EVENTS is the fullest event record, and of the drift slots the whole interface's extremes:
# every rank learns them at the same agreement.
FLAG_NONFINITE, FLAG_RUNAWAY, FLAG_REACH, FLAG_FOLD, FLAG_MPI = 1, 2, 4, 8, 16
(L_BITS, L_STEP, L_BLOCK, L_ROW, L_COL, L_VALUE, L_EVENTS, L_TOP_HI, L_TOP_LO, L_BOTTOM_HI, L_BOTTOM_LO) = range(11)
L_DRIFT = L_TOP_HI            # the four drift slots, in this order
L_SIZE = 12
assert L_SIZE <= REDUCE_WORDS          # the exchange's reduction holds them all
DRIFT_QUANTA = 64             # per a: drift extremes are rounded outward to 1/64 a
NO_SITES = -(1 << 60)         # a drift slot of a rank without such sites (below any extreme)

# The halo's drift box (``Diag.halo``), in DRIFT_QUANTA per a and in the order of the drift slots (outward):
# H_LIMIT: the box's edges; H_MARGIN: the room an edge must keep at an agreement (half its skin), and at
# least twice the drift's growth since the last agreement; H_PREV: the extremes at the last agreement;
# H_GROWTH: their growth over the last agreement interval (what a rebuild reads to widen the skin).
H_LIMIT, H_MARGIN, H_PREV, H_GROWTH = 0, 4, 8, 12
H_SIZE = 16

# Phase timers (ns), accumulated in ``timers`` over one step in TIME_EVERY: [interface bonds, early tasks,
# post, other tasks, complete] and the number of timed steps; checks are timed whenever they run, frames one
# in TIME_EVERY (T_FRAME_SAMPLES of them); timers[T_CLOCK:T_CLOCK+2] is the clock's scratch space.  A clock
# read costs 25 ns on bare metal and about 100 ns in a VM: sampling keeps it out of the step's cost.
T_IFACE, T_EARLY, T_POST, T_LATE, T_COMPLETE, T_CHECK, T_FRAMES, T_SAMPLES, T_CLOCK = range(9)
T_FRAME_SAMPLES = 10
T_SIZE = 11
TIME_EVERY = 16

# Heartbeat: the step the loop last passed (every check), read without locks by the monitor thread.
BEAT_STEP, BEAT_IN_LOOP = 0, 1
BEAT_SIZE = 2

# Why ``advance`` returned: the end, the frame buffer full, a problem, some rank's event record past
# ``Params.event_limit`` (the caller writes frames and events out, then calls again), or the interface's drift
# near the edge of the box its halos cover (the caller rebuilds the slabs and halos, then calls again).
DONE, FRAMES_FULL, STOPPED, EVENTS_FULL, REBUILD = 0, 1, 2, 3, 4


@njit(cache=True, _nrt=False, inline="always")      # inlined: a call would be compiled for each set of constants
def _flag(flags, bit, step, block, row, col, value):
    if flags[L_BITS] == 0:
        flags[L_STEP] = step
        flags[L_BLOCK] = block
        flags[L_ROW] = row
        flags[L_COL] = col
        flags[L_VALUE] = np.int64(min(max(value, -9e12), 9e12) * 1e6) if np.isfinite(value) else -1
    flags[L_BITS] |= bit


@njit(cache=True, _nrt=False, forceinline=True)
def _drive(cx, cy, zx, zy, px, py, r, j, s, mask, K, blk, drive, drive_on, shift, prm, bud, energy):
    """Drive node (r, j) of the driven face, once it has had its free update u(n+1) in ``px``.

    Prescribed (DRIVE_SPRING unset): its x becomes drive0 + v0 (t(n+1) - t_drive); with KEEP_FORCE keep the
    force that took, (x_drive - x_free) / C.  Through a spring (DRIVE_SPRING): the node feels
    f = k_s (x_loader(n) - u_x(n)) from a rigid loader at x_loader(n) = drive0 + v0 (t(n) - t_drive), added
    as any force is, u(n+1) += C f; KEEP_FORCE keeps f.  With DRIVE_XY its y stays where it was
    (u_y(n+1) = u_y(n): held since the drive started).  A node of the face outside ``drive.rows`` has no
    slot (index -1) and is left free.

    Returns the node's exact shares of the budget on its final u(n+1) (``stencil._budget``; the caller
    drops what the row kernel counted on the free update) and adds the drive's work
    f . (u(n+1) - u(n-1))/2, with the force that holds y if held, to the slot's total; ``bud.prev`` holds the
    slot's u(n-1)."""
    slot = drive.index[r, j]
    if slot < 0:
        return 0, 0, 0
    xf, yf = px[r, j], py[r, j]
    if drive_on & DRIVE_SPRING:
        f = prm.spring * (drive.drive0[r, j] + (shift - prm.v0dt) - cx[r, j])
        px[r, j] += prm.cf * f
    else:
        target = drive.drive0[r, j] + shift
        f = (target - xf) * prm.inv_cf
        px[r, j] = target
    if drive_on & KEEP_FORCE:
        drive.force[slot] = f
    fy = 0.0
    if drive_on & DRIVE_XY:
        py[r, j] = cy[r, j]
        fy = (float(cy[r, j]) - float(yf)) * float(prm.inv_cf)
    x0, y0 = bud.prev[0, slot], bud.prev[1, slot]
    bg.add(bud.work, slot, 0.5 * (float(f) * (float(px[r, j]) - x0) + fy * (float(py[r, j]) - y0)))
    bud.prev[0, slot] = cx[r, j]
    bud.prev[1, slot] = cy[r, j]
    fux, fuy = px[r, j], py[r, j]            # unused unless on a frame's step: the body drag needs no force
    if energy:
        fux, fuy = masked_force(cx, cy, r, j, s, K, blk, mask)
    return budget_shares(cx[r, j], cy[r, j], x0, y0, px[r, j], py[r, j], fux, fuy, bud.cs, prm.drag, energy)


@njit(cache=True, _nrt=False, fastmath={'contract'}, inline="always")
def _rows(t0, t1, tasks, cur_x, cur_y, z_x, z_y, nxt_x, nxt_y, K, prm, ex, ey, zeros, drive, drive_on, shift, gy,
          bud, energy):
    """Row tasks t0..t1 of one block (FULL, NO_UP, NO_DOWN); bond forces on the field (z_x, z_y).  Their
    exact shares of the budget go to ``bud.acc`` (``kernels.budget``).  A FULL task may cover several rows
    (``kernels.rect``); the others, and driven ones, cover one."""
    cf = prm.cf
    damped, drag, rated = prm.damped, prm.drag, prm.rated
    cs = bud.cs
    zero = like(0, cf)
    ds = 0
    ks = 0
    es = 0
    for t in range(t0, t1):
        tk = tasks[t]
        r, j0, n, s = tk.row, tk.j0, tk.n, tk.s
        g = gy if tk.load else zero
        if tk.kind == FULL:
            d, k, e = rect_full(cur_x, cur_y, z_x, z_y, nxt_x, nxt_y, r, tk.rows, j0, n, s, K, tk.block, damped,
                                drag, rated, energy, cs)
        elif tk.extra:
            d, k, e = row_edge(cur_x, cur_y, z_x, z_y, nxt_x, nxt_y, r, j0, n, s, K, tk.block, damped,
                               tk.kind == NO_DOWN, cf, ex, ey, zero, g, drag, rated, energy, cs)
        else:
            d, k, e = row_edge(cur_x, cur_y, z_x, z_y, nxt_x, nxt_y, r, j0, n, s, K, tk.block, damped,
                               tk.kind == NO_DOWN, cf, zeros, zeros, zero, g, drag, rated, energy, cs)
        if tk.drive and drive_on:        # a driven row (T0): every node's share taken on its final u(n+1)
            mask = bg.ALL if tk.kind == FULL else (bg.NO_UP_MASK if tk.kind == NO_UP else bg.NO_DOWN_MASK)
            d = k = e = 0
            for j in range(j0, j0 + n):
                d2, k2, e2 = _drive(cur_x, cur_y, z_x, z_y, nxt_x, nxt_y, r, j, s, mask, K, tk.block, drive, drive_on,
                                    shift, prm, bud, energy)
                d += d2
                k += k2
                e += e2
        ds += d
        ks += k
        es += e
    _deposit_shares(bud, ds, ks, es, energy)


@njit(cache=True, _nrt=False, forceinline=True)
def _deposit_shares(bud, ds, ks, es, energy):
    bg.deposit(bud.acc, bg.Q_DAMP, ds)
    if energy:
        bg.deposit(bud.acc, bg.Q_KIN, ks)
        bg.deposit(bud.acc, bg.Q_EL, es)


@njit(cache=True, _nrt=False, fastmath={'contract'}, inline="always")
def _nodes(t0, t1, tasks, cur_x, cur_y, z_x, z_y, nxt_x, nxt_y, K, prm, ex, ey, drive, drive_on, shift, gy, bud,
           energy):
    """MASKED single-node tasks t0..t1 of one block (its edge columns), each a column of ``rows`` nodes."""
    one = np.int64(1)          # a variable: a constant would compile ``rect_full``'s loops again, for it
    cf = prm.cf
    damped, drag, rated = prm.damped, prm.drag, prm.rated
    cs = bud.cs
    zero = like(0, cf)
    ds = 0
    ks = 0
    es = 0
    for t in range(t0, t1):
        tk = tasks[t]
        j = tk.j0
        if tk.mask == ALL_BONDS and tk.mask2 == ALL_BONDS and not (tk.extra or tk.load or tk.drive):
            # Interior nodes at a slab's edge: a column of segments of one, by the row segments' own arithmetic
            # (the serial run updates them inside a segment).
            d, k, e = rect_full(cur_x, cur_y, z_x, z_y, nxt_x, nxt_y, tk.row, tk.rows, j, tk.n, tk.s, K, tk.block,
                                damped, drag, rated, energy, cs)
            ds += d
            ks += k
            es += e
            continue
        for i in range(tk.rows):
            r = tk.row + i
            s = tk.s ^ (i & 1)
            mask = tk.mask2 if i & 1 else tk.mask
            if mask == ALL_BONDS and not tk.extra and not tk.load:
                d, k, e = rect_full(cur_x, cur_y, z_x, z_y, nxt_x, nxt_y, r, one, j, tk.n, s, K, tk.block, damped,
                                    drag, rated, energy, cs)
            else:
                fx = ex[j] if tk.extra else zero
                fy = (ey[j] if tk.extra else zero) + (gy if tk.load else zero)
                d, k, e = node_masked(cur_x, cur_y, z_x, z_y, nxt_x, nxt_y, r, j, s, K, tk.block, damped, mask, cf,
                                      fx, fy, drag, rated, energy, cs)
            if tk.drive and drive_on and drive.index[r, j] >= 0:
                d, k, e = _drive(cur_x, cur_y, z_x, z_y, nxt_x, nxt_y, r, j, s, mask, K, tk.block, drive, drive_on,
                                 shift, prm, bud, energy)
            ds += d
            ks += k
            es += e
    _deposit_shares(bud, ds, ks, es, energy)


# One call per phase: the loop over the two blocks and the row and node kernels compiled into one function.  A
# call passes every array descriptor of its arguments (a few hundred words): four calls of ``_rows`` and
# ``_nodes`` per phase cost about as much as updating a few hundred nodes.  Not inlined into ``_step``, which
# calls it twice: numba would type, lower and optimise the kernels once for each place.  The phase arrives as a
# variable (``np.int64(EARLY)``), not a constant: a constant compiled a version per phase (60 s of compile, not 47).
# Compiled with the kernels' flags (``contract``): numba inlines ``_rows`` and ``_nodes`` with their caller's.
@njit(cache=True, _nrt=False, fastmath={'contract'})
def _phase(phase, sched, cur, src, nxt, K, prm, iface, plan, drive, drive_on, shift, gy, bud, energy):
    """The tasks of one phase (EARLY, LATE) of both blocks.  In the LATE phase MPI is given a chance to
    move the halo messages halfway through (``progress``, a no-op on one rank)."""
    tasks = sched.tasks
    for b in range(2):
        p = sched.ptr[phase, b]
        if b == 0:                      # the substrate (BOTTOM) block, never driven
            cx, cy, zx, zy, px, py, ex, ey, on = (cur.bx, cur.by, src.bx, src.by, nxt.bx, nxt.by, iface.exb_x,
                                                  iface.exb_y, 0)
        else:                           # the sliding (TOP) block
            cx, cy, zx, zy, px, py, ex, ey, on = (cur.tx, cur.ty, src.tx, src.ty, nxt.tx, nxt.ty, iface.ext_x,
                                                  iface.ext_y, drive_on)
        if p[NODES] > p[ROWS]:
            _rows(p[ROWS], p[NODES], tasks, cx, cy, zx, zy, px, py, K, prm, ex, ey, iface.zeros, drive, on, shift, gy,
                  bud, energy)
        if phase == LATE and b == 0:
            progress(plan)          # an MPI call (half a microsecond): only where there is work to hide it behind
        if p[END] > p[NODES]:
            _nodes(p[NODES], p[END], tasks, cx, cy, zx, zy, px, py, K, prm, ex, ey, drive, on, shift, gy, bud, energy)


@njit(cache=True, _nrt=False, inline="always")
def _tasks(phase, sched, cur, src, nxt, K, prm, iface, plan, drive, drive_on, shift, gy, bud, energy):
    """The tasks of one phase, if it has any (a rank without peers has no EARLY tasks, one without overlap no
    LATE ones)."""
    if sched.ptr[phase, 1, END] > sched.ptr[phase, 0, ROWS]:
        _phase(phase, sched, cur, src, nxt, K, prm, iface, plan, drive, drive_on, shift, gy, bud, energy)


@njit(cache=True, _nrt=False)
def _row_moves(cx, cy, px, py, r, j0, n):
    """Sum over a row segment of |u(n+1) - u(n)|^2 (a^2): NaN or inf if any node is not finite."""
    acc = 0.0
    for j in range(j0, j0 + n):
        dx = float(px[r, j]) - float(cx[r, j])
        dy = float(py[r, j]) - float(cy[r, j])
        acc += dx * dx + dy * dy
    return acc


@njit(cache=True, _nrt=False)
def _check(n, tasks, cur, nxt, prm, iface, flags):
    """Owned nodes of u(n+1): finite, and moved less than ``prm.jump`` a in the step (else: runaway);
    the substrate's owned interface sites each to the right of its left neighbour (the re-bonding search
    walks the row in x order; ``kernels.interface._span``).

    A row whose summed squared moves stays below jump^2 cannot hold a runaway node;
    only other rows are searched node by node.
    """
    g = iface.geom
    jump = prm.jump
    j2 = jump * jump
    for t in range(tasks.shape[0]):
        tk = tasks[t]
        b, j0, nn = tk.block, tk.j0, tk.n
        for r in range(tk.row, tk.row + tk.rows):
            if b == 0:
                if _row_moves(cur.bx, cur.by, nxt.bx, nxt.by, r, j0, nn) <= j2:
                    continue
                cx, cy, px, py, base = cur.bx, cur.by, nxt.bx, nxt.by, g.bbase
            else:
                if _row_moves(cur.tx, cur.ty, nxt.tx, nxt.ty, r, j0, nn) <= j2:
                    continue
                cx, cy, px, py, base = cur.tx, cur.ty, nxt.tx, nxt.ty, g.tbase
            for j in range(j0, j0 + nn):
                if not (np.isfinite(px[r, j]) and np.isfinite(py[r, j])):
                    _flag(flags, FLAG_NONFINITE, n + 1, b, r, j + base, np.inf)
                    return
                dx = float(px[r, j]) - float(cx[r, j])
                dy = float(py[r, j]) - float(cy[r, j])
                d = np.sqrt(dx * dx + dy * dy)
                if d > jump:
                    _flag(flags, FLAG_RUNAWAY, n + 1, b, r, j + base, d)
                    return
    if prm.has_iface and not prm.rigid:
        br = prm.brow
        for i in range(max(g.bown0, g.blo + 1), g.bown1):
            gap = 1.0 + (float(nxt.bx[br, i]) - float(nxt.bx[br, i - 1]))
            if not gap > 0.0:
                _flag(flags, FLAG_FOLD, n + 1, 0, br, i + g.bbase, gap)
                return


@njit(cache=True, _nrt=False, forceinline=True)
def _loader_shift(n, prm):
    """How far the loader has moved at t(n + 1), v0 (t(n + 1) - t_drive) (a): the driven face's prescribed x
    for u(n + 1); a spring drive reads its loader at t(n), this less v0 dt.  From ``n_hold`` on the loader
    holds still where it was at t(n_hold) (for the springs: this plus v0 dt)."""
    n_ds = prm.n_drive_start
    if n + 1 <= prm.n_hold:
        return like(prm.v0 * ((n + 1 - n_ds) * prm.dt), prm.cf)
    held = like(prm.v0 * ((prm.n_hold - n_ds) * prm.dt), prm.cf)
    return held + prm.v0dt if prm.drive & DRIVE_SPRING else held


@njit(cache=True, _nrt=False, inline="always")
def _step(n, n1, cur, nxt, z, plan, sched, K, prm, iface, drive, diag, bud):
    """Step n -> n + 1: read ``cur`` (u(n)), overwrite ``nxt`` (u(n - 1)) with u(n + 1); ``n1`` is where the
    call that takes this step ends."""
    n_ds = prm.n_drive_start
    drive_on = prm.drive if n >= n_ds else 0         # DRIVE_X or DRIVE_XY once the drive runs
    if drive_on and (n + 1 >= n1 or (n + 1 - n_ds) % prm.frame_every == 0):
        drive_on |= KEEP_FORCE
    # A step that ends on a frame: the kernels also sum the state's energy H(n + 1/2) that frame records.
    energy = n + 1 >= n_ds and (n + 1 - n_ds) % prm.frame_every == 0
    if energy:
        bud.acc[bg.Q_KIN, :] = 0
        bud.acc[bg.Q_EL, :] = 0
    if prm.drive and n == n_ds:
        d0 = drive.drive0
        for r in range(d0.shape[0]):
            for j in range(d0.shape[1]):
                d0[r, j] = cur.tx[r, j]
    lf = ramp_share(n, prm.n_ramp)
    gy = like(lf * prm.fext, prm.cf)
    shift = _loader_shift(n, prm)
    flags, tm = diag.flags, diag.timers
    clk = tm[T_CLOCK:T_CLOCK + 2]
    timed = n % TIME_EVERY == 0           # sample the phase times (a clock read is 25 to 100 ns)
    t0 = now_ns(clk) if timed else 0
    if prm.has_iface:
        br = prm.brow
        ik.update(n, cur.tx[PAD], cur.ty[PAD], cur.bx[br], cur.by[br], nxt.tx[PAD], nxt.ty[PAD], nxt.bx[br],
                  nxt.by[br], iface, bud.sites)
        if iface.reach[0] >= 0:
            _flag(flags, FLAG_REACH, n, 1, 0, iface.reach[0], 0.0)
            iface.reach[0] = -1
        if not ik.coverage(cur.tx[PAD], cur.bx[br], iface.geom):
            _flag(flags, FLAG_REACH, n, 1, 0, -1, 0.0)
    src = cur
    if prm.rated:              # the bonds' damping: bond forces on z = u(n) + g (u(n) - u(n-1)), whole blocks
        rate_field(cur.bx, cur.by, nxt.bx, nxt.by, z.bx, z.by, K[0, K_RATE])
        rate_field(cur.tx, cur.ty, nxt.tx, nxt.ty, z.tx, z.ty, K[1, K_RATE])
        src = z
    t1 = now_ns(clk) if timed else 0
    _tasks(np.int64(EARLY), sched, cur, src, nxt, K, prm, iface, plan, drive, drive_on, shift, gy, bud, energy)
    t2 = now_ns(clk) if timed else 0
    err = post(plan, nxt.bx, nxt.by, nxt.tx, nxt.ty, iface.bonds)
    t3 = now_ns(clk) if timed else 0
    _tasks(np.int64(LATE), sched, cur, src, nxt, K, prm, iface, plan, drive, drive_on, shift, gy, bud, energy)
    t4 = now_ns(clk) if timed else 0
    err |= complete(plan, nxt.bx, nxt.by, nxt.tx, nxt.ty, iface.bonds)
    if timed:
        t5 = now_ns(clk)
        tm[T_IFACE] += t1 - t0
        tm[T_EARLY] += t2 - t1
        tm[T_POST] += t3 - t2
        tm[T_LATE] += t4 - t3
        tm[T_COMPLETE] += t5 - t4
        tm[T_SAMPLES] += 1
    if err != 0:
        _flag(flags, FLAG_MPI, n, -1, -1, -1, float(err))


@njit(cache=True, _nrt=False)
def _budget_start(cur, old, drive, bud):
    """The budget's totals start with the drive (step n_drive_start): zero (with what a restart before it
    carried over), and each driven slot's u(n-1)."""
    for acc in (bud.work, bud.base):
        acc[:, :] = 0.0
    bud.sites[:, :, :] = 0.0
    bud.acc[bg.Q_DAMP, :] = 0
    idx = drive.index
    for r in range(idx.shape[0]):
        for j in range(idx.shape[1]):
            slot = idx[r, j]
            if slot >= 0:
                bud.prev[0, slot] = old.tx[r, j]
                bud.prev[1, slot] = old.ty[r, j]


@njit(cache=True, _nrt=False)
def _energies(n, cur, old, sched, prm, iface, bud, out):
    """This rank's share of the budget at a frame (``kernels.budget``), out[:, term]: the float pairs in rows
    0-1 (the running totals with what a restart carried over, the interface bonds' and the contact springs'
    staggered energy, the load's sum), the kernels' exact sums in rows 2-4 (the damping; the kinetic and bulk
    elastic energy the step that ended here left)."""
    out[:, :] = 0.0
    bg.total(bud.work, out, bg.W_DRIVE)
    for k in range(len(bg.SITE_TERMS)):
        bg.total(bud.sites[k], out, bg.SITE_TERMS[k])
    for k in range(bg.N_TERMS):
        bg.add(out, k, bud.base[0, k])
        bg.add(out, k, bud.base[1, k])
    bg.exact_parts(bud.acc, bg.Q_DAMP, bud.scale, out, bg.DAMPING)
    bg.exact_parts(bud.acc, bg.Q_KIN, bud.scale, out, bg.KINETIC)
    bg.exact_parts(bud.acc, bg.Q_EL, bud.scale, out, bg.ELASTIC)
    tasks = sched.tasks
    for t in range(tasks.shape[0]):
        tk = tasks[t]
        if tk.load:
            for r in range(tk.row, tk.row + tk.rows):
                bg.load_sum(cur.ty, old.ty, r, tk.j0, tk.n, out)
    if prm.has_iface:
        br = prm.brow
        ik.staggered(n, cur.tx[PAD], cur.ty[PAD], cur.bx[br], cur.by[br], old.tx[PAD], old.ty[PAD], old.bx[br],
                     old.by[br], iface, out)
        if iface.rules.contact > 0:
            ik.contact_staggered(cur.tx[PAD], cur.ty[PAD], cur.bx[br], cur.by[br], old.tx[PAD], old.ty[PAD],
                                 old.bx[br], old.by[br], iface, out)



@njit(cache=True, _nrt=False, inline="always")      # both advance and _record call it: inlined in each
def _frame_of(n, prm):
    """The frame step n records (counted from the drive's start), or -1 if n is not a frame's step."""
    k = n - prm.n_drive_start
    fe = prm.frame_every
    if k < 0 or k % fe != 0 or k // fe >= prm.n_frames:
        return -1
    return k // fe


@njit(cache=True, _nrt=False)
def _record(n, cur, old, sched, K, prm, iface, drive, bud, frames, tm):
    """Record frame k at step n if due; False when the buffer is full (the caller must flush first)."""
    f = _frame_of(n, prm)
    if f < 0:
        return True
    timed = f % TIME_EVERY == 0
    t0 = now_ns(tm[T_CLOCK:T_CLOCK + 2]) if timed else 0
    k = f + prm.frame_offset               # the frame's index in the file
    cursor = frames.cursor
    if k <= cursor[C_LAST]:
        return True
    slot = k - cursor[C_BASE]
    if slot >= frames.step.shape[0]:
        return False
    if prm.has_iface:
        br = prm.brow
        ik.record(n, cur.tx[PAD], cur.ty[PAD], cur.bx[br], cur.by[br], old.tx[PAD], old.ty[PAD], old.bx[br],
                  old.by[br], iface, slot, frames)
    # The drive's force in the step that ended here (0 before the drive's first step).
    on = prm.drive != 0 and n > prm.n_drive_start
    for i in range(drive.force.shape[0]):
        frames.fdrive[slot, i] = drive.force[i] if on else 0.0
    _energies(n, cur, old, sched, prm, iface, bud, frames.energy[slot])
    frames.step[slot] = n
    cursor[C_COUNT] = slot + 1
    cursor[C_LAST] = k
    if timed:
        tm[T_FRAMES] += now_ns(tm[T_CLOCK:T_CLOCK + 2]) - t0
        tm[T_FRAME_SAMPLES] += 1
    return True


@njit(cache=True, _nrt=False, inline="always")
def _level(lv, n):
    """The Level holding u(n)."""
    if n % 2 == 0:
        return Level(lv.bx0, lv.by0, lv.tx0, lv.ty0)
    return Level(lv.bx1, lv.by1, lv.tx1, lv.ty1)


@njit(cache=True, _nrt=False)
def _drift(nxt, prm, iface, flags):
    """This rank's drift extremes into the drift slots of ``flags`` (DRIFT_QUANTA per a, rounded outward): of
    u_x(n + 1) - D over its OWNED block interface sites, and of u_x(n + 1) over its OWNED substrate ones."""
    g = iface.geom
    q = float(DRIFT_QUANTA)
    for k in range(4):
        flags[L_DRIFT + k] = NO_SITES
    if g.town1 > g.town0:
        hi, lo = -np.inf, np.inf
        for j in range(g.town0, g.town1):
            v = float(nxt.tx[PAD, j]) - prm.shift
            hi, lo = max(hi, v), min(lo, v)
        flags[L_TOP_HI] = np.int64(np.ceil(hi * q))
        flags[L_TOP_LO] = np.int64(np.ceil(-lo * q))
    if g.bown1 > g.bown0 and not prm.rigid:
        br = prm.brow
        hi, lo = -np.inf, np.inf
        for i in range(g.bown0, g.bown1):
            v = float(nxt.bx[br, i])
            hi, lo = max(hi, v), min(lo, v)
        flags[L_BOTTOM_HI] = np.int64(np.ceil(hi * q))
        flags[L_BOTTOM_LO] = np.int64(np.ceil(-lo * q))


@njit(cache=True, _nrt=False)
def _near_edge(g, halo):
    """Whether the agreed drift extremes ``g`` (every rank has the same) came near an edge of the halo's box: an
    edge keeps H_MARGIN, and at least twice the extreme's growth since the last agreement, of room.  Records
    the extremes and their growth in ``halo``; the same answer on every rank."""
    near = False
    for k in range(4):
        e = g[L_DRIFT + k]
        if e == NO_SITES:
            continue
        grow = max(e - halo[H_PREV + k], 0)
        halo[H_GROWTH + k] = grow
        halo[H_PREV + k] = e
        if halo[H_LIMIT + k] - e < max(halo[H_MARGIN + k], 2 * grow):
            near = True
    return near


@njit(cache=True, nogil=True)
def advance(n0, n1, lv, plan, sched, K, prm, iface, drive, frames, diag, bud):
    """Advance the state from step n0 towards n1; returns (n, why) with why DONE, FRAMES_FULL, STOPPED,
    EVENTS_FULL or REBUILD.

    ``diag.flags`` are this rank's problems (first one kept, with its step and place); ``diag.gflags``
    their MAX over all ranks, refreshed every ``prm.check_every`` steps; ``diag.timers`` accumulates the
    time of each phase (ns, ``T_*``); ``diag.beat[BEAT_STEP]`` follows the step.  Runs without the GIL,
    so the monitor thread can speak while a long call runs.
    """
    n = n0
    check = prm.check_every
    beat = diag.beat
    beat[BEAT_STEP] = n
    beat[BEAT_IN_LOOP] = 1
    tm = diag.timers
    stepped = False
    # The step n -> n + 1 stands before the frame of step n in the text (the loop enters at the frame): numba
    # types and compiles the callees in the order they are written, so the frames' kernels come last, and a
    # job's helper rank has compiled them into the cache by then (``record_signature``, ``engine.compile``).
    while True:
        if stepped:
            cur = _level(lv, n)
            nxt = _level(lv, n + 1)
            _step(n, n1, cur, nxt, Level(lv.zbx, lv.zby, lv.ztx, lv.zty), plan, sched, K, prm, iface, drive, diag,
                  bud)
            if (n + 1) % check == 0:
                t0 = now_ns(tm[T_CLOCK:T_CLOCK + 2])
                _check(n, sched.tasks, cur, nxt, prm, iface, diag.flags)
                g = diag.gflags
                diag.flags[L_EVENTS] = iface.events.count[0]
                if prm.follow:
                    _drift(nxt, prm, iface, diag.flags)
                for i in range(g.shape[0]):
                    g[i] = diag.flags[i]
                reduce_max(plan, g)
                tm[T_CHECK] += now_ns(tm[T_CLOCK:T_CLOCK + 2]) - t0
                beat[BEAT_STEP] = n + 1
                if g[L_BITS] != 0:
                    beat[BEAT_IN_LOOP] = 0
                    return n + 1, STOPPED
                if prm.follow and _near_edge(g, diag.halo):
                    beat[BEAT_IN_LOOP] = 0
                    return n + 1, REBUILD
                if g[L_EVENTS] > prm.event_limit:
                    beat[BEAT_IN_LOOP] = 0
                    return n + 1, EVENTS_FULL
            n += 1
        stepped = True
        cur = _level(lv, n)
        if n == prm.n_drive_start:          # before its frame: the drive's start is the budget's zero
            _budget_start(cur, _level(lv, n + 1), drive, bud)
        # Only a frame's step calls ``_record``: a call passes every array of its arguments (hundreds of
        # words), which every step paid to learn it had nothing to record.
        due = _frame_of(n, prm) >= 0
        ok = _record(n, cur, _level(lv, n + 1), sched, K, prm, iface, drive, bud, frames, tm) if due else True
        if not ok:
            beat[BEAT_IN_LOOP] = 0
            return n, FRAMES_FULL
        if n >= n1:
            beat[BEAT_IN_LOOP] = 0
            return n, DONE


def record_signature(lv, sched, K, prm, iface, drive, frames, diag, bud) -> tuple:
    """The argument types with which ``advance``, called with these, calls ``_record``: compiling ``_record``
    for them (``_record.compile``) fills numba's cache with what compiling ``advance`` would compile."""
    from numba import typeof
    cur = _level.py_func(lv, 0)
    return tuple(typeof(a) for a in (np.int64(0), cur, cur, sched, K, prm, iface, drive, bud, frames, diag.timers))
