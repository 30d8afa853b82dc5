"""The compiled time loop: many Verlet steps per call, between which Python writes output.

Responsible for the order of one step and the load phases (ramp F_N, settle
with damping, drive), and for stopping where Python must act: the end of the
requested steps, a full buffer of interface frames, or a problem (a state
that is not finite or grows without bound, a bond out of the halo's reach, a
substrate site that drifted further than the re-bonding window assumes).

One step n -> n+1, at positions u(n) (level n % 2; level (n+1) % 2 holds
u(n-1) and receives u(n+1)):

 1. record interface frame k if n is its step (u(n), bonds as they entered);
 2. interface bonds: break, re-form, forces (``kernels.interface``), on every
    local interface site, OWNED and HALO; check that the halo still covers them;
 3. the schedule's early tasks: the rows and columns peers keep as HALO;
 4. ``exchange(POST)``: send them with the bond state, post the receives;
 5. the remaining tasks, while messages travel;
 6. ``exchange(COMPLETE)``: HALO copies now hold u(n+1) and the bonds of step n.

Every ``check_every`` steps the loop checks the state it owns and all ranks
agree (``exchange(REDUCE)``) whether to stop; they stop at the same step.
The exchange plan is passed in: on one rank it has no peers and no
communicator, and the exchange does nothing.
"""
from collections import namedtuple

import numpy as np
from numba import njit

from ..parallel.exchange import COMPLETE, POST, PROGRESS, REDUCE, exchange
from ..parallel.layout import ALL_BONDS, FULL, NO_DOWN, PAD
from .kernels import interface as ik
from .kernels.clock import now_ns
from .kernels.floats import like
from .kernels.stencil import node_masked, row_edge, row_full

# State: each block as [row, column] arrays, x and y apart, at two Verlet levels.
Levels = namedtuple("Levels", "bx0 by0 bx1 by1 tx0 ty0 tx1 ty1")
# Interface arrays, indexed by local column of the block's row 0 (top) or the substrate's interface row.
Iface = namedtuple("Iface", "partner x0 claim taken ext_x ext_y exb_x exb_y zeros geom consts counters reach")
# Interface frame buffer: ``cap`` frames of the OWNED top sites.
Frames = namedtuple("Frames", "intact partner ux uy sxy syy step cursor")

# Integer parameters ``ip``.
(I_NRAMP, I_NDS, I_DRIVE, I_FRAME_EVERY, I_NFRAMES, I_CHECK, I_HAS_IFACE, I_RIGID, I_BROW, I_FOFF) = range(10)
I_SIZE = 10
# ip[I_DRIVE]: 0 no drive; DRIVE_X the driven face's x is prescribed; DRIVE_XY its y is also held where
# it was when the drive started (``drive.hold = "xy"``).
DRIVE_X, DRIVE_XY = 1, 2
# Float parameters ``fp`` (float64).
F_DT, F_V0, F_FEXT, F_JUMP = range(4)
# State-type parameters ``sp``: C = dt^2/(1 + zeta dt/2), the factor on forces; 1 if zeta > 0.
S_CF, S_DAMPED = range(2)

# Frame cursor: [first frame index held in the buffer, frames held, last frame index recorded].
C_BASE, C_COUNT, C_LAST = range(3)

# Flags: [status bits, step, block, row, global column, value*1e6 as int].
FLAG_NONFINITE, FLAG_RUNAWAY, FLAG_REACH, FLAG_DRIFT, FLAG_MPI = 1, 2, 4, 8, 16
(L_BITS, L_STEP, L_BLOCK, L_ROW, L_COL, L_VALUE) = range(6)
L_SIZE = 8

# Phase timers (ns), accumulated in ``timers`` over one step in TIME_EVERY: [interface bonds, early tasks,
# post, other tasks, complete] and the number of timed steps; checks and frames are timed whenever they
# run; timers[T_CLOCK:T_CLOCK+2] is the clock's scratch space.
T_IFACE, T_EARLY, T_POST, T_LATE, T_COMPLETE, T_CHECK, T_FRAMES, T_SAMPLES, T_CLOCK = range(9)
T_SIZE = 11
TIME_EVERY = 16

# Why ``advance`` returned.
DONE, FRAMES_FULL, STOPPED = 0, 1, 2


@njit(cache=True, _nrt=False)
def _flag(flags, bit, step, block, row, col, value):
    if flags[L_BITS] == 0:
        flags[L_STEP] = step
        flags[L_BLOCK] = block
        flags[L_ROW] = row
        flags[L_COL] = col
        flags[L_VALUE] = np.int64(min(max(value, -9e12), 9e12) * 1e6) if np.isfinite(value) else -1
    flags[L_BITS] |= bit


@njit(cache=True, _nrt=False, fastmath={'contract'})
def _rows(t0, t1, tasks, cx, cy, px, py, K, sp, ex, ey, zeros, drive0, drive_on, shift, gy):
    """Row tasks t0..t1 of one block (FULL, NO_UP, NO_DOWN)."""
    cf = sp[S_CF]
    damped = sp[S_DAMPED] != 0
    zero = like(0, cf)
    for t in range(t0, t1):
        b, r, j0, n, kind, extra, load, drive, s = (tasks[t, 0], tasks[t, 1], tasks[t, 2], tasks[t, 3],
                                                    tasks[t, 4], tasks[t, 6], tasks[t, 7], tasks[t, 8], tasks[t, 10])
        g = gy if load else zero
        if kind == FULL:
            row_full(cx, cy, px, py, r, j0, n, s, K, b, damped)
        elif extra:
            row_edge(cx, cy, px, py, r, j0, n, s, K, b, damped, kind == NO_DOWN, cf, ex, ey, zero, g)
        else:
            row_edge(cx, cy, px, py, r, j0, n, s, K, b, damped, kind == NO_DOWN, cf, zeros, zeros, zero, g)
        if drive and drive_on:
            for j in range(j0, j0 + n):
                px[r, j] = drive0[r, j] + shift
                if drive_on == DRIVE_XY:
                    py[r, j] = cy[r, j]


@njit(cache=True, _nrt=False, fastmath={'contract'})
def _nodes(t0, t1, tasks, cx, cy, px, py, K, sp, ex, ey, drive0, drive_on, shift, gy):
    """MASKED single-node tasks t0..t1 of one block (its edge columns)."""
    cf = sp[S_CF]
    damped = sp[S_DAMPED] != 0
    zero = like(0, cf)
    for t in range(t0, t1):
        b, r, j, mask, extra, load, drive, s = (tasks[t, 0], tasks[t, 1], tasks[t, 2], tasks[t, 5], tasks[t, 6],
                                                tasks[t, 7], tasks[t, 8], tasks[t, 10])
        if mask == ALL_BONDS and not extra and not load:
            row_full(cx, cy, px, py, r, j, 1, s, K, b, damped)   # an interior node cut off by a slab edge
        else:
            fx = ex[j] if extra else zero
            fy = (ey[j] if extra else zero) + (gy if load else zero)
            node_masked(cx, cy, px, py, r, j, s, K, b, damped, mask, cf, fx, fy)
        if drive and drive_on:
            px[r, j] = drive0[r, j] + shift
            if drive_on == DRIVE_XY:
                py[r, j] = cy[r, j]


@njit(cache=True, _nrt=False)
def _tasks(phase, ptr, tasks, cbx, cby, ctx, cty, nbx, nby, ntx, nty, K, sp, iface, drive0, drive_on, shift, gy,
           plan=None):
    """The tasks of one phase (0: early, 1: the rest); ``ptr[phase, block]`` = [rows start, nodes start, end].
    With ``plan`` (the late phase), MPI is given a chance to move the halo messages halfway through."""
    p = ptr[phase]
    _rows(p[0, 0], p[0, 1], tasks, cbx, cby, nbx, nby, K, sp, iface.exb_x, iface.exb_y, iface.zeros, drive0,
          0, shift, gy)
    if plan is not None:
        exchange(PROGRESS, plan, nbx, nby, ntx, nty, iface.partner, iface.x0, iface.counters)
    _nodes(p[0, 1], p[0, 2], tasks, cbx, cby, nbx, nby, K, sp, iface.exb_x, iface.exb_y, drive0, 0, shift, gy)
    _rows(p[1, 0], p[1, 1], tasks, ctx, cty, ntx, nty, K, sp, iface.ext_x, iface.ext_y, iface.zeros, drive0,
          drive_on, shift, gy)
    _nodes(p[1, 1], p[1, 2], tasks, ctx, cty, ntx, nty, K, sp, iface.ext_x, iface.ext_y, drive0, drive_on, shift,
           gy)


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
def _check(n, tasks, cbx, cby, ctx, cty, nbx, nby, ntx, nty, ip, jump, iface, flags):
    """Owned nodes of u(n+1): finite, and moved less than ``jump`` a in the step (else: runaway);
    the substrate's owned interface sites within ``drift`` of their columns.

    A row whose summed squared moves stays below jump^2 cannot hold a runaway node;
    only other rows are searched node by node.
    """
    g = iface.geom
    base_b, base_t = g[ik.G_BBASE], g[ik.G_TBASE]
    j2 = jump * jump
    for t in range(tasks.shape[0]):
        b, r, j0, nn = tasks[t, 0], tasks[t, 1], tasks[t, 2], tasks[t, 3]
        if b == 0:
            if _row_moves(cbx, cby, nbx, nby, r, j0, nn) <= j2:
                continue
            cx, cy, px, py, base = cbx, cby, nbx, nby, base_b
        else:
            if _row_moves(ctx, cty, ntx, nty, r, j0, nn) <= j2:
                continue
            cx, cy, px, py, base = ctx, cty, ntx, nty, base_t
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
    if ip[I_HAS_IFACE] != 0 and ip[I_RIGID] == 0:
        drift = iface.consts[ik.P_DRIFT]
        br = ip[I_BROW]
        for i in range(g[ik.G_BOWN0], g[ik.G_BOWN1]):
            if not abs(nbx[br, i]) <= drift:
                _flag(flags, FLAG_DRIFT, n + 1, 0, br, i + base_b, float(nbx[br, i]))
                return


@njit(cache=True, _nrt=False)
def _step(n, cbx, cby, ctx, cty, nbx, nby, ntx, nty, plan, tasks, ptr, K, ip, fp, sp, iface, drive0,
          flags, tm):
    n_ds = ip[I_NDS]
    drive_on = ip[I_DRIVE] if n >= n_ds else 0        # DRIVE_X or DRIVE_XY once the drive runs
    if ip[I_DRIVE] != 0 and n == n_ds:
        for r in range(drive0.shape[0]):
            for j in range(drive0.shape[1]):
                drive0[r, j] = ctx[r, j]
    nr = ip[I_NRAMP]
    lf = 1.0 if nr == 0 else min(1.0, n / nr)
    gy = like(lf * fp[F_FEXT], sp[S_CF])
    shift = like(fp[F_V0] * ((n + 1 - n_ds) * fp[F_DT]), sp[S_CF])
    clk = tm[T_CLOCK:T_CLOCK + 2]
    timed = n % TIME_EVERY == 0           # sample the phase times: a clock read costs about 25 ns
    t0 = now_ns(clk) if timed else 0
    if ip[I_HAS_IFACE] != 0:
        br = ip[I_BROW]
        ik.update(ctx[PAD], cty[PAD], cbx[br], cby[br], iface.partner, iface.x0, iface.taken, iface.claim,
                  iface.geom, iface.consts, iface.counters, iface.reach, iface.ext_x, iface.ext_y, iface.exb_x,
                  iface.exb_y)
        if iface.reach[0] >= 0:
            _flag(flags, FLAG_REACH, n, 1, 0, iface.reach[0], 0.0)
            iface.reach[0] = -1
        if not ik.coverage(ctx[PAD], cbx[br], iface.geom):
            _flag(flags, FLAG_REACH, n, 1, 0, -1, 0.0)
    t1 = now_ns(clk) if timed else 0
    _tasks(0, ptr, tasks, cbx, cby, ctx, cty, nbx, nby, ntx, nty, K, sp, iface, drive0, drive_on, shift, gy)
    t2 = now_ns(clk) if timed else 0
    err = exchange(POST, plan, nbx, nby, ntx, nty, iface.partner, iface.x0, flags)
    t3 = now_ns(clk) if timed else 0
    _tasks(1, ptr, tasks, cbx, cby, ctx, cty, nbx, nby, ntx, nty, K, sp, iface, drive0, drive_on, shift, gy, plan)
    t4 = now_ns(clk) if timed else 0
    err |= exchange(COMPLETE, plan, nbx, nby, ntx, nty, iface.partner, iface.x0, flags)
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
def _record(n, lv, ip, iface, frames, tm):
    """Record frame k at step n if due; False when the buffer is full (the caller must flush first)."""
    k = n - ip[I_NDS]
    fe = ip[I_FRAME_EVERY]
    if k < 0 or k % fe != 0 or k // fe >= ip[I_NFRAMES]:
        return True
    t0 = now_ns(tm[T_CLOCK:T_CLOCK + 2])
    k = k // fe + ip[I_FOFF]               # the frame's index in the file (a restart may change the cadence)
    cur = frames.cursor
    if k <= cur[C_LAST]:
        return True
    slot = k - cur[C_BASE]
    if slot >= frames.step.shape[0]:
        return False
    if n % 2 == 0:
        tx, ty, bx, by = lv.tx0, lv.ty0, lv.bx0, lv.by0
    else:
        tx, ty, bx, by = lv.tx1, lv.ty1, lv.bx1, lv.by1
    if ip[I_HAS_IFACE] != 0:
        br = ip[I_BROW]
        ik.record(tx[PAD], ty[PAD], bx[br], by[br], iface.partner, iface.x0, iface.geom, iface.consts, slot,
                  frames.intact, frames.partner, frames.ux, frames.uy, frames.sxy, frames.syy)
    frames.step[slot] = n
    cur[C_COUNT] = slot + 1
    cur[C_LAST] = k
    tm[T_FRAMES] += now_ns(tm[T_CLOCK:T_CLOCK + 2]) - t0
    return True


@njit(cache=True)
def advance(n0, n1, lv, plan, tasks, ptr, K, ip, fp, sp, iface, drive0, frames, flags, gflags, tm):
    """Advance the state from step n0 towards n1; returns (n, why) with why DONE, FRAMES_FULL or STOPPED.

    ``flags`` are this rank's problems (first one kept, with its step and place);
    ``gflags`` their MAX over all ranks, refreshed every ``check_every`` steps;
    ``tm`` accumulates the time of each phase (ns, ``T_*``).
    """
    n = n0
    check = ip[I_CHECK]
    jump = fp[F_JUMP]
    while True:
        ok = _record(n, lv, ip, iface, frames, tm)
        if not ok:
            return n, FRAMES_FULL
        if n >= n1:
            return n, DONE
        if n % 2 == 0:
            _step(n, lv.bx0, lv.by0, lv.tx0, lv.ty0, lv.bx1, lv.by1, lv.tx1, lv.ty1, plan, tasks, ptr, K,
                  ip, fp, sp, iface, drive0, flags, tm)
        else:
            _step(n, lv.bx1, lv.by1, lv.tx1, lv.ty1, lv.bx0, lv.by0, lv.tx0, lv.ty0, plan, tasks, ptr, K,
                  ip, fp, sp, iface, drive0, flags, tm)
        if (n + 1) % check == 0:
            t0 = now_ns(tm[T_CLOCK:T_CLOCK + 2])
            if n % 2 == 0:
                _check(n, tasks, lv.bx0, lv.by0, lv.tx0, lv.ty0, lv.bx1, lv.by1, lv.tx1, lv.ty1, ip, jump, iface,
                       flags)
            else:
                _check(n, tasks, lv.bx1, lv.by1, lv.tx1, lv.ty1, lv.bx0, lv.by0, lv.tx0, lv.ty0, ip, jump, iface,
                       flags)
            for i in range(gflags.shape[0]):
                gflags[i] = flags[i]
            exchange(REDUCE, plan, lv.bx0, lv.by0, lv.tx0, lv.ty0, iface.partner, iface.x0, gflags)
            tm[T_CHECK] += now_ns(tm[T_CLOCK:T_CLOCK + 2]) - t0
            if gflags[L_BITS] != 0:
                return n + 1, STOPPED
        n += 1
