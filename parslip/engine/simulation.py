"""One rank's simulation: builds the state and drives the compiled loop between outputs.

Responsible for the Python side of a run: which steps the compiled loop
(``engine.loop.advance``) runs per call, writing interface frames in blocks
and snapshots at their steps, progress, and turning the loop's flags into
errors that name the step, the place and the likely cause.  The exchange
plan is passed in: one rank runs the same loop with a plan of no peers.

Time is internal (a/c_ref) inside; every time the user sees is in l/c_r.
"""
from __future__ import annotations

import math
import time

import numpy as np

from ..errors import NonFiniteError, SlipReachError
from ..io.contract import ENERGY_SINKS, ENERGY_SOURCES
from ..model.interface import BONDS
from ..model.lattice import TOP
from ..parallel.exchange import build_plan
from ..parallel.layout import PAD, build_layout, owned_site_counts, task_ranges
# RUNAWAY_JUMP (a): a node that moves this far in one step is running away.  It lives with the scene
# limits, which refuse a drive that would move its face that far per step by prescription.
from ..scene.limits import RUNAWAY_JUMP
from . import loop as L
from .kernels import budget as bg
from .kernels import exact
from .kernels.scheme import ramp_share
from ..scene.memory import CHECK_EVERY, event_room, frame_buffer
from .state import State

# Work per compiled call, in node updates: about 0.3 s, so progress and output stay timely.
CHUNK_UPDATES = 2e8
class Simulation:
    """One rank's share of the lattice and the loop that advances it."""

    def __init__(self, setup, comm=None, dtype=None, buffer_frames: int = 0, buffer_events: int = 0):
        self.setup = st = setup
        self.comm = comm if comm is not None and comm.Get_size() > 1 else None
        rank, size = (comm.Get_rank(), comm.Get_size()) if self.comm else (0, 1)
        self.rank, self.size = rank, size
        sc = st.scene
        self.layout = build_layout(st.lattice, rank, size, st.reach, st.drive.mode)
        self.dtype = np.dtype(dtype or st.dtype)
        lat = st.lattice
        # The frame buffer holds the same number of frames on every rank: sized from the largest slab's site
        # count, which every rank computes from the slab bounds; the event record is written out at an
        # agreement of the ranks (see the collective rule in ``loop``).
        counts = owned_site_counts(lat, self.layout.bounds)
        widest = int(counts.max())
        self.event_limit, capacity = event_room(int(counts[rank]) if lat.has_interface else 0, buffer_events)
        self.state = State(st, self.layout, self.dtype, event_capacity=capacity)
        self.plan = build_plan(self.layout, self.dtype, self.comm)
        self.sched = L.Schedule(tasks=self.layout.tasks, ptr=task_ranges(self.layout.tasks))
        cf = st.damping.force_factor(st.dt)
        self.params = L.Params(
            n_ramp=st.n_ramp, n_drive_start=st.n_drive_start, drive=st.drive.code,
            frame_every=st.frame_every, n_frames=st.n_frames, frame_offset=0, check_every=CHECK_EVERY,
            has_iface=bool(lat.has_interface), rigid=bool(lat.rigid),
            brow=int(self.layout.blocks[0].prow(self.layout.blocks[0].rows - 1)), dt=float(st.dt), v0=float(st.v0),
            fext=float(-sc["load.FN"] / lat.top.cols if lat.has_interface else 0.0), jump=float(RUNAWAY_JUMP),
            cf=self.dtype.type(cf), inv_cf=self.dtype.type(1.0 / cf), damped=st.damping.damped,
            event_limit=self.event_limit, spring=self.dtype.type(st.drive.spring), rated=st.damping.rated,
            drag=st.damping.damped and sc["output.energy"] == "checked",
            v0dt=self.dtype.type(st.v0 * st.dt))
        self.diag = L.Diag(flags=np.zeros(L.L_SIZE, np.int64), gflags=np.zeros(L.L_SIZE, np.int64),
                           timers=np.zeros(L.T_SIZE, np.int64), beat=np.zeros(L.BEAT_SIZE, np.int64))
        nsites = max(self.state.owned_sites().stop - self.state.owned_sites().start, 0)
        cap = buffer_frames if buffer_frames > 0 else frame_buffer(widest, st.n_frames)
        self.buffer_frames = cap = int(min(cap, st.n_frames))
        ndrive = len(self.state.drive.force)
        self.frames = L.Frames(intact=np.zeros((cap, nsites), np.uint8), partner=np.zeros((cap, nsites), np.int32),
                               ux=np.zeros((cap, nsites)), uy=np.zeros((cap, nsites)), sxy=np.zeros((cap, nsites)),
                               syy=np.zeros((cap, nsites)), fx=np.zeros((cap, nsites)),
                               fdrive=np.zeros((cap, ndrive)), energy=np.zeros((cap, 5, bg.N_TERMS)),
                               step=np.zeros(cap, np.int64),
                               cursor=np.array([0, 0, -1], np.int64))
        self.budget = self._budget(cf)
        self.energy_base = None          # rank 0: the state's terms at the drive's start (``budget_frames``)
        # Steps per compiled call before any agreement: from the lattice and rank count, the same everywhere.
        self.chunk = int(np.clip(CHUNK_UPDATES * size / max(lat.n_nodes, 1), 64, 200_000))
        self.n = 0
        self.drive_clock = None          # (time.monotonic(), time.process_time(), step) when the drive began
        self.monitor = None              # engine.monitor.Monitor of the run, if any: told the phase
        self._snap = {st.n_drive_start + k: j for j, k in enumerate(st.snapshot_steps)}
        self.snapshots_total = len(self._snap)
        self.snapshots_written = 0
        self.last_frame_step = -1
        self.events_written = 0          # bond events in the output file (over all ranks)

    # ---------------------------------------------------------------- steps --
    @property
    def counters(self) -> np.ndarray:
        """[bond breaks, re-formations] among this rank's interface sites so far."""
        return self.state.iface.counters

    def advance(self, n_end: int):
        """Run the compiled loop to step ``n_end`` or until it must stop; returns why it returned."""
        s = self.state
        n, why = L.advance(self.n, n_end, s.levels, self.plan, self.sched, s.K, self.params, s.iface, s.drive,
                           self.frames, self.diag, self.budget)
        self.n = int(n)
        return why

    def _budget(self, cf: float):
        """The energy budget's running totals on this rank (``loop.Budget``), all zero."""
        st, s = self.setup, self.state
        dt, dmp = st.dt, st.damping
        slots = len(s.drive.force)
        sites = s.iface.bonds.shape[1]
        sd = dmp.zeta / (4.0 * dt) if dmp.damped else 0.0
        scale = exact.scales(sd)
        cs = np.array([sd * scale[bg.Q_DAMP], -0.5 * scale[bg.Q_DAMP] / cf, 0.5 * scale[bg.Q_KIN] / (dt * dt),
                       -0.5 * scale[bg.Q_EL] / cf])
        return L.Budget(acc=np.zeros((bg.N_Q, 2), np.int64), work=np.zeros((2, slots)),
                        sites=np.zeros((len(bg.SITE_TERMS), 2, sites)), base=np.zeros((2, bg.N_TERMS)),
                        prev=np.zeros((2, slots)), cs=cs, scale=scale)

    def step(self):
        """One step, n -> n + 1 (tests)."""
        self.run(until=self.n + 1)

    # ------------------------------------------------- state by global id --
    @property
    def u(self) -> np.ndarray:
        """u(n) of the OWNED nodes, (n_owned, 2) in global id order (a); a copy."""
        return self.state.owned_u(self.n)

    @property
    def u_prev(self) -> np.ndarray:
        """u(n - 1) of the OWNED nodes; a copy."""
        return self.state.owned_u(self.n - 1)

    def set_u(self, u: np.ndarray, u_prev: np.ndarray | None = None):
        """Set u(n) and u(n - 1) (default: u, at rest) of the OWNED nodes, in global id order.

        One rank only: HALO copies are not refreshed until the next step's exchange.
        """
        self.state.set_owned_u(self.n, u)
        self.state.set_owned_u(self.n - 1, u if u_prev is None else u_prev)

    def load_factor(self, n: int | None = None) -> float:
        """min(1, n / n_ramp): the share of F_N acting at step n."""
        return ramp_share(self.n if n is None else n, self.setup.n_ramp)

    def energy(self, n: int | None = None, load: float | None = None) -> float:
        """Potential energy of this rank's part at step n (default: now), in m c^2."""
        n = self.n if n is None else n
        return self.state.potential_energy(n, self.load_factor(n) if load is None else load)

    def compile(self):
        """The first call of the compiled loop, taking no step: numba compiles it (or loads it from its
        cache) here, so that progress rates and the ETA never count it.  On several ranks one rank per
        kernel cache compiles and the others then load, the snapshots' stress kernel included
        (``engine.compile``); returns how it went (``FirstCall``).  Collective."""
        from .compile import first_call
        self._phase("compile")

        def call():
            self.advance(self.n)
            if self.snapshots_total:
                self.state.node_fields(self.n)
        return first_call(self.comm, call)

    def run(self, writer=None, until: int | None = None, control=None):
        """Advance to step ``until`` (default: the end), writing frames and snapshots on the way.

        ``control`` (``engine.control.RunControl``) agrees, between calls of the compiled loop and on every
        rank at the same step, whether to stop for a checkpoint or for good: then ``run`` returns its
        action with every frame so far written, and a later ``run`` carries on.  Returns None at the end.
        Every call of the loop ends at a step computed from data all ranks hold (see ``engine.loop``).
        """
        st = self.setup
        end = st.n_steps if until is None else until
        chunk = self.chunk
        while True:
            self._snapshot(writer)
            if self.n >= end:          # a stop asked for at the last step finds the run complete, not stopped
                break
            if control is not None:
                action, steps = control.agree(self)
                chunk = steps or chunk
                if action is not None:
                    self._flush(writer)
                    return action
            target = min(end, self.n + chunk, min((k for k in self._snap if k > self.n), default=end),
                         control.next_stop(self.n) if control is not None else end,
                         st.n_drive_start if self.n < st.n_drive_start else end)
            if self.drive_clock is None and self.n >= st.n_drive_start:
                self.drive_clock = (time.monotonic(), time.process_time(), self.n)
            self._phase("loop")
            why = self.advance(target)
            if why in (L.FRAMES_FULL, L.EVENTS_FULL):
                self._flush(writer)
                continue
            if why == L.STOPPED:
                self._fail(writer)
        self.advance(self.n)                 # the frame of the last step, if it is one
        self._flush(writer)
        return None

    def _phase(self, name: str):
        if self.monitor is not None:
            self.monitor.phase(name)

    # --------------------------------------------------------------- output --
    def output_spec(self):
        """What the writer (``io.output.Output``) needs of this run, as a frozen ``RunSpec``."""
        from ..io.output import RunSpec
        s, lat, lay = self.state, self.setup.lattice, self.layout
        return RunSpec(setup=self.setup, rank=lay.rank, size=lay.size, col_range=tuple(lay.col_range),
                       owned_sites=tuple(lay.owned_sites()) if lat.has_interface else (0, 0),
                       node0=int(s.gid[0]) if s.n_owned else 0, site0=s.site0() if lat.has_interface else 0,
                       driven_gid=s.driven_gid, frames_total=self.frames_total,
                       snapshots_total=self.snapshots_total, buffer_frames=self.buffer_frames,
                       events_written=self.events_written)

    @property
    def frames_total(self) -> int:
        """Interface frames in the output file once this run ends (earlier runs' frames included)."""
        return int(self.params.frame_offset) + self.setup.n_frames

    @property
    def frames_written(self) -> int:
        return int(self.frames.cursor[L.C_BASE])

    def frame_time(self, steps: np.ndarray) -> np.ndarray:
        """Times (l/c_r from the drive start) of frames recorded at these steps."""
        st = self.setup
        return st.to_lcr((np.asarray(steps) - st.n_drive_start) * st.dt)

    def drive_time(self, k: np.ndarray) -> np.ndarray:
        """Times (l/c_r) of drive steps ``k`` (negative before the drive), as ``frame_time`` computes them."""
        st = self.setup
        return st.to_lcr(np.asarray(k) * st.dt)

    def _flush(self, writer):
        """Write out the frames and the bond events held (collective: every rank calls it at the same step)."""
        self._phase("write frames")
        fr = self.frames
        count = int(fr.cursor[L.C_COUNT])
        if count:
            self.last_frame_step = int(fr.step[count - 1])
        if writer is not None and count:
            base = int(fr.cursor[L.C_BASE])
            writer.interface_frames(base, count, fr, self.frame_time(fr.step[:count]), self.budget_frames(count))
        fr.cursor[L.C_BASE] += count
        fr.cursor[L.C_COUNT] = 0
        ev = self.state.iface.events
        m = int(ev.count[0])
        if writer is not None:
            nds = self.setup.n_drive_start
            self.events_written = writer.interface_events(
                self.events_written, ev.step[:m] - nds, ev.site[:m], ev.kind[:m], ev.partner[:m], ev.energy[:m],
                ev.traction[:m], self.drive_time)
        ev.count[0] = 0

    # ----------------------------------------------------------- checkpoints --
    def checkpoint_parts(self) -> dict:
        """This rank's share of a checkpoint (``io.checkpoint``), by global id: node and site arrays."""
        s = self.state
        lat = self.setup.lattice
        d0 = np.zeros(s.n_owned, s.dtype)
        top = s.own_block == TOP
        d0[top] = s.drive.drive0[s.own_prow[top], s.own_j[top]]
        fd = np.zeros(s.n_owned, s.dtype)
        fd[np.searchsorted(s.gid, s.driven_gid)] = s.drive.force
        parts = {"gid": s.gid, "u": s.owned_u(self.n, s.dtype), "u_prev": s.owned_u(self.n - 1, s.dtype),
                 "drive0": d0, "drive_force": fd}
        if lat.has_interface:
            sl = s.owned_sites()
            parts["site"] = np.arange(sl.stop - sl.start) + s.site0()
            parts.update(s.owned_bonds())
        else:
            parts["site"] = np.zeros(0, np.int64)
            parts.update({name: np.zeros(0, s.dtype) for name in BONDS.checkpoint})
        return parts

    def restore(self, arrays: dict, attrs: dict):
        """Continue from a checkpoint: the state at its step, the output cursor after what it wrote.

        Every rank takes its OWNED part by global id, then halo exchanges fill the HALO copies."""
        self._phase("restore")
        s, st = self.state, self.setup
        self.n = n = int(attrs["step"])
        for level, name in ((n, "u"), (n - 1, "u_prev")):
            s.set_owned_u(level, arrays[name][s.gid])
        top = s.own_block == TOP
        s.drive.drive0[s.own_prow[top], s.own_j[top]] = arrays["drive0"][s.gid[top]]
        s.drive.force[:] = arrays["drive_force"][s.driven_gid]
        if st.lattice.has_interface:
            sl = s.owned_sites()
            sites = np.arange(sl.stop - sl.start) + s.site0()
            s.set_owned_bonds({name: arrays[name][sites] for name in BONDS.checkpoint})
        if self.comm is not None:
            # Both levels: a rule may read u(n - 1) of HALO sites too (the slip velocity).
            from ..parallel.halo_mpi import mpi_complete, mpi_post
            for level in (n - 1, n):
                bx, by, tx, ty = s.level(level)
                mpi_post(self.plan, bx, by, tx, ty, s.iface.bonds)
                mpi_complete(self.plan, bx, by, tx, ty, s.iface.bonds)
        if self.rank == 0:
            s.iface.counters[:] = [int(v) for v in attrs["counters"]]
        self.events_written = int(attrs["events_written"])
        # The output carries on after what the checkpointed run wrote, at this scene's cadence.
        written = int(attrs["frames_written"])
        self.last_frame_step = last = int(attrs["last_frame_step"])
        fe, nds = st.frame_every, st.n_drive_start
        k_first = 0 if last < nds else (last - nds) // fe + 1
        self.params = self.params._replace(frame_offset=written - k_first)
        self.frames.cursor[:] = [written, 0, written - 1]
        snaps = int(attrs["snapshots_written"])
        later = sorted(k for k in self._snap if k > n)
        self._snap = {k: snaps + m for m, k in enumerate(later)}
        self.snapshots_total = snaps + len(later)
        self.snapshots_written = snaps
        self._energy_restore(attrs)

    # ---------------------------------------------------------- energy budget --
    def _pairs(self, parts) -> np.ndarray:
        """Rank 0: [count, term] the correctly rounded sums (``math.fsum``) of every rank's pairs ``parts``
        ([count, 2, term] each), so the same bits on any rank count (``kernels.budget``)."""
        stack = np.stack(parts)                                   # [rank, count, 2, term]
        count, terms = stack.shape[1], stack.shape[3]
        return np.array([[math.fsum(stack[:, k, :, t].ravel()) for t in range(terms)] for k in range(count)])

    def _to_root(self, x):
        return [x] if self.comm is None else self.comm.gather(x, root=0)

    def budget_frames(self, count: int) -> dict | None:
        """Rank 0: the energy budget of the ``count`` frames held (m c_r^2), since the drive started: the
        sources (contract ``ENERGY_SOURCES``: work_drive, work_normal, formed, contact_switched) equal the
        sinks (``ENERGY_SINKS``: elastic, kinetic, contact, damping, broken) plus the residual (contract
        ``ENERGY_DATASETS``); collective.  The damping is summed in the loop with ``output.energy =
        "checked"`` and the body drag, else it is the balance and the residual NaN.  The state's terms at the drive's start come from its frame
        (or from the checkpoint a run continues); without them (a checkpoint that predates the budget)
        they read NaN."""
        fr = self.frames
        parts = self._to_root(fr.energy[:count])
        if self.rank != 0:
            return None
        tot = self._pairs(parts)
        if self.energy_base is None and fr.cursor[L.C_BASE] == 0 and fr.step[0] == self.setup.n_drive_start:
            self.energy_base = tot[0, list(bg.STATE)].copy()
        base = self.energy_base if self.energy_base is not None else np.full(len(bg.STATE), np.nan)
        e = 1.0 / self.setup.material.c_r ** 2
        change = {term: (tot[:, term] - base[k]) * e for k, term in enumerate(bg.STATE) if term != bg.LOAD_Y}
        out = {"work_drive": tot[:, bg.W_DRIVE] * e, "damping": tot[:, bg.DAMPING] * e,
               "broken": tot[:, bg.BROKEN] * e, "formed": tot[:, bg.FORMED] * e,
               "kinetic": change[bg.KINETIC], "elastic": change[bg.ELASTIC],
               "work_normal": 0.5 * self.params.fext * (tot[:, bg.LOAD_Y] - base[bg.STATE.index(bg.LOAD_Y)]) * e,
               "contact": change[bg.CONTACT], "contact_switched": tot[:, bg.SWITCHED] * e}
        balance = sum(out[k] for k in ENERGY_SOURCES) - sum(out[k] for k in ENERGY_SINKS if k != "damping")
        if self.params.drag or self.setup.damping.zeta == 0:
            out["residual"] = balance - out["damping"]
        else:
            # Not summed in the loop (``output.energy = "balance"``; the bonds' dashpots always, as their work
            # would take a second stencil pass every step): the damping is what the other terms leave, and
            # the residual is not measured.
            out["damping"], out["residual"] = balance, np.full(count, np.nan)
        return out

    def _energy_checkpoint(self) -> dict:
        """The budget's part of a checkpoint (collective): the running totals over all ranks, each as a pair
        (fsum and its exact remainder), and the state's terms at the drive's start."""
        b = self.budget
        mine = np.zeros((2, bg.N_TERMS))
        bg.total(b.work, mine, bg.W_DRIVE)
        for acc, term in zip(b.sites, bg.SITE_TERMS):
            bg.total(acc, mine, term)
        for k in range(bg.N_TERMS):                 # what an earlier restart carried over, without a rounding
            bg.add(mine, k, b.base[0, k])
            bg.add(mine, k, b.base[1, k])
        # The kernels' exact sums: the damping's running total, and the kinetic and elastic energy of the
        # last step that ended on a frame (a frame not yet recorded when the run stopped reads them after).
        quanta = [int(b.acc[q, 0]) * (1 << bg.WORD) + int(b.acc[q, 1]) for q in range(bg.N_Q)]
        parts = self._to_root((mine, quanta))
        attrs = None
        if self.rank == 0:
            stack = np.stack([p[0] for p in parts])                # [rank, 2, term]
            hi = np.array([math.fsum(stack[:, :, t].ravel()) for t in range(bg.N_TERMS)])
            lo = np.array([math.fsum(list(stack[:, :, t].ravel()) + [-hi[t]]) for t in range(bg.N_TERMS)])
            totals = [sum(p[1][q] for p in parts) for q in range(bg.N_Q)]      # exact, in quanta
            base = self.energy_base if self.energy_base is not None else np.full(len(bg.STATE), np.nan)
            attrs = {"energy_totals": np.array([hi, lo]), "energy_base": np.asarray(base, np.float64),
                     "energy_quanta": np.array([[t >> bg.WORD, t & ((1 << bg.WORD) - 1)] for t in totals],
                                               np.int64)}
        return attrs if self.comm is None else self.comm.bcast(attrs, root=0)

    def _energy_restore(self, attrs: dict):
        """Continue the budget from a checkpoint: rank 0 carries the totals, every rank its slots' u(n-1)."""
        b, s = self.budget, self.state
        tot = attrs.get("energy_totals")
        b.base[:] = 0.0
        b.acc[:] = 0
        if self.rank == 0:
            b.base[:] = np.nan if tot is None else self._later_terms(tot, bg.N_TERMS)
            if tot is not None:
                b.acc[:] = np.asarray(attrs["energy_quanta"], np.int64)
            # None where not known yet (a checkpoint before the drive's start): the drive's first frame gives it.
            base = attrs.get("energy_base")
            known = base is not None and not np.isnan(base).all()
            self.energy_base = self._later_terms(np.asarray(base)[None], len(bg.STATE))[0] if known else None
        u_prev = s.owned_u(self.n - 1)
        b.prev[:] = u_prev[np.searchsorted(s.gid, s.driven_gid)].T

    def _later_terms(self, values, n: int) -> np.ndarray:
        """A checkpoint's budget terms ([rows, terms]) padded to ``n`` terms: a checkpoint written before the
        contact's terms existed carries none, 0 without a contact and unknown (NaN) with one."""
        values = np.asarray(values, np.float64)
        fill = np.nan if self.setup.law.contact else 0.0
        return np.concatenate([values, np.full((values.shape[0], n - values.shape[1]), fill)], axis=1)

    def checkpoint_attrs(self) -> dict:
        """The scalar part of a checkpoint, collective (the event counters are summed over the ranks)."""
        st = self.setup
        counters = self.counters.copy()
        if self.comm is not None:
            counters = self.comm.allreduce(counters)
        return {**self._energy_checkpoint(), "step": self.n, "time_lcr": st.to_lcr((self.n - st.n_drive_start) * st.dt),
                "frames_written": self.frames_written, "last_frame_step": self.last_frame_step,
                "events_written": self.events_written,
                "snapshots_written": self.snapshots_written, "counters": counters,
                "omega_max": st.omega_max, "omega_method": st.omega_method, "dt": st.dt, "n_ranks": self.size,
                "precision": self.dtype.name}

    def _snapshot(self, writer):
        j = self._snap.get(self.n)
        if j is None or j < self.snapshots_written:      # not a snapshot step, or written already
            return
        self.snapshots_written = j + 1
        if writer is None:
            return
        self._phase("snapshot")
        st = self.setup
        t = st.to_lcr((self.n - st.n_drive_start) * st.dt)
        pos, vel, sig = self.state.node_fields(self.n)
        writer.snapshot(j, t, pos, vel, sig, self.state.owned_partner())

    # --------------------------------------------------------------- errors --
    def _gather(self, x):
        return [x] if self.comm is None else self.comm.allgather(x)

    def _fail(self, writer):
        """Every rank stopped at the same step: find the first problem on any rank and raise it."""
        st = self.setup
        mine = self.diag.flags.copy()
        reports = [r for r in self._gather(mine) if r[L.L_BITS]]
        first = min(reports, key=lambda r: r[L.L_STEP])
        bits, step = int(first[L.L_BITS]), int(first[L.L_STEP])
        # Frames recorded at or after the failing step hold a broken state: drop them.
        fr = self.frames
        keep = int(np.searchsorted(fr.step[:int(fr.cursor[L.C_COUNT])], step, side="left"))
        fr.cursor[L.C_COUNT] = keep
        ev = self.state.iface.events          # and so do events of those steps (each rank's are in step order)
        ev.count[0] = int(np.searchsorted(ev.step[:int(ev.count[0])], step, side="left"))
        self._flush(writer)
        t = st.to_lcr((step - st.n_drive_start) * st.dt)
        if bits & (L.FLAG_NONFINITE | L.FLAG_RUNAWAY):
            raise NonFiniteError(self._describe_node(first, t))
        if bits & L.FLAG_REACH:
            slip = max(self._gather(self.state.max_top_slip(self.n)))
            col = int(first[L.L_COL])
            what = (f"the bond or re-bonding window of the interface site at column {col} reached past the substrate "
                    f"sites its rank holds" if col >= 0 else "the halo no longer covered the interface's reach")
            raise SlipReachError(
                f"interface slip reached {slip:.3g} a (the block relative to the substrate) at step {step} "
                f"(t = {t:.4g} l/c_r): {what}, beyond "
                f"interface.slip_reach = {st.slip_reach:.3g} a that the MPI halo covers; rerun with --set "
                f"interface.slip_reach={max(2 * slip, st.slip_reach + 2):.3g}")
        if bits & L.FLAG_FOLD:
            raise NonFiniteError(
                f"the substrate's interface row folded at step {step} (t = {t:.4g} l/c_r): its site at column "
                f"{int(first[L.L_COL])} stood {first[L.L_VALUE] / 1e6:.3g} a to the right of its left neighbour, and "
                f"re-bonding needs the row in x order; the substrate is too soft for this load (raise "
                f"material.bottom_kn or lower load.FN)")
        raise NonFiniteError(f"MPI error {first[L.L_VALUE] / 1e6:.0f} in the halo exchange at step {step}")

    def _describe_node(self, f, t):
        st, lat = self.setup, self.setup.lattice
        step, b, r, c = int(f[L.L_STEP]), int(f[L.L_BLOCK]), int(f[L.L_ROW]) - PAD, int(f[L.L_COL])
        B = lat.blocks[b]
        gid = int(lat.gid(b, r, c))
        x, y = c + float(B.offset(r)), B.y0 + r * np.sqrt(3) / 2
        node = (f"node {gid} ({'top' if b == TOP else 'bottom'} block, row {r}, column {c}, x = {x:.4g} a, "
                f"y = {y:.4g} a)")
        from ..io.cache import cache_dir
        from ..scene.derive import CACHE_HITS
        cause = "a time step above the stability limit (try a smaller time.safety)"
        if (st.omega_max, st.omega_method) in CACHE_HITS:
            cause += f"; omega_max was read from the disk cache in {cache_dir()}: delete it if in doubt"
        site_row = r == 0 if b == TOP else r == lat.bottom.rows - 1
        if lat.has_interface and site_row and st.law.contact == 0:
            # Seen at l = 500 under F_N = 30: the bonds broke, nothing held the block up, it sank into the
            # substrate and a site met it in one step; the same run with a contact ends normally.
            cause += ("; or, at this interface site: a site whose bond broke feels no contact "
                      "(interface.contact = 0), so under F_N the block can sink into the substrate until a site "
                      f"meets it; rerun with a contact, e.g. --set interface.contact={st.law.ky:g}")
        if f[L.L_BITS] & L.FLAG_NONFINITE:
            return (f"state became non-finite at step {step} (t = {t:.4g} l/c_r from drive start) at {node}; "
                    f"likely cause: {cause}")
        return (f"state grew without bound: at step {step} (t = {t:.4g} l/c_r from drive start) the {node} "
                f"moved {f[L.L_VALUE] / 1e6:.3g} a in one step (faster than any wave of the lattice); likely cause: "
                f"{cause}; output written so far is kept")
