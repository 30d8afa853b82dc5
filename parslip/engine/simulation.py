"""One rank's simulation: builds the state and drives the compiled loop between outputs.

Responsible for the Python side of a run: which steps the compiled loop
(``engine.loop.advance``) runs per call, writing interface frames in blocks
and snapshots at their steps, progress, and turning the loop's flags into
errors that name the step, the place and the likely cause.  The exchange
plan is passed in: one rank runs the same loop with a plan of no peers.

Time is internal (a/c_ref) inside; every time the user sees is in l/c_r.
"""
from __future__ import annotations

import time

import numpy as np

from ..errors import NonFiniteError, SlipReachError
from ..io.contract import ENERGY_SINKS, ENERGY_SOURCES
from ..model.interface import BONDS, NEVER
from ..model.lattice import TOP
from ..model.physics import ROW_HEIGHT
from ..parallel.exact_sum import exact_sums
from ..parallel.exchange import build_plan, release
from ..parallel.layout import PAD, build_layout, owned_site_counts, task_ranges
from ..parallel.migrate import NODES, SITES, Placement, block_columns, redistribute
# RUNAWAY_JUMP (a): a node that moves this far in one step is running away.  It lives with the scene
# limits, which refuse a drive that would move its face that far per step by prescription.
from ..scene.limits import RUNAWAY_JUMP
from . import follow
from . import loop as L
from .kernels import budget as bg
from .kernels import exact
from .kernels.scheme import ramp_share
from ..scene.memory import CHECK_EVERY, event_room, frame_buffer
from .prestress import Hold
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
        self.dtype = np.dtype(dtype or st.dtype)
        lat = st.lattice
        self.buffer_events = buffer_events
        self._buffer_frames = buffer_frames
        # The halos follow the interface's drift (``engine.follow``) on several ranks unless the scene fixes a slip
        # reach; one rank holds every site and needs no halo.
        follow = size > 1 and lat.has_interface and st.reach.drift is not None
        self.rebuilds = 0                # how many times the slabs and halos followed the drift
        cf = st.damping.force_factor(st.dt)
        self.params = L.Params(
            n_ramp=st.n_ramp, n_drive_start=st.n_drive_start, drive=st.drive.code,
            frame_every=st.frame_every, n_frames=st.n_frames, frame_offset=0, check_every=CHECK_EVERY,
            has_iface=bool(lat.has_interface), rigid=bool(lat.rigid),
            brow=int(lat.bottom.rows - 1 + PAD), dt=float(st.dt), v0=float(st.v0),
            fext=float(-sc["load.FN"] / lat.top.cols if lat.has_interface else 0.0), jump=float(RUNAWAY_JUMP),
            cf=self.dtype.type(cf), inv_cf=self.dtype.type(1.0 / cf), damped=st.damping.damped,
            event_limit=event_room(0, buffer_events)[0], spring=self.dtype.type(st.drive.spring),
            rated=st.damping.rated, drag=st.damping.damped and sc["output.energy"] == "checked",
            v0dt=self.dtype.type(st.v0 * st.dt), follow=follow, shift=0, n_hold=NEVER)
        self.diag = L.Diag(flags=np.zeros(L.L_SIZE, np.int64), gflags=np.zeros(L.L_SIZE, np.int64),
                           timers=np.zeros(L.T_SIZE, np.int64), beat=np.zeros(L.BEAT_SIZE, np.int64),
                           halo=np.zeros(L.H_SIZE, np.int64))
        self.frames = None
        self._build(build_layout(lat, rank, size, st.reach, st.drive.mode, overlap=st.overlap))
        # The slabs of no drift: each rank's nodes are one contiguous range of global ids, in which the output
        # file's node datasets are written (the first layout's, as nothing has slid yet).
        self.io_placement = Placement(self.layout.bounds, (0, 0))
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
        self.hold = Hold(st, self.comm)  # drive.prestress: where the loader stops

    def release(self):
        """Free what the exchange plan holds in MPI (its requests, its shared windows); collective over the
        ranks of a node.  The simulation cannot step afterwards."""
        if getattr(self, "plan", None) is not None:
            release(self.plan)
            self.plan = None

    def _build(self, layout):
        """This rank's arrays for ``layout``, all zero: the state, the exchange plan, the schedule, the frame
        buffer (the frames held so far must have been written) and the budget's running totals, and the
        drift box its halos serve (``Diag.halo``)."""
        st, lat, rank = self.setup, self.setup.lattice, self.rank
        self.layout = layout
        # The frame buffer holds the same number of frames on every rank: sized from the largest slab's site
        # count, which every rank computes from the slab bounds; the event record is written out at an
        # agreement of the ranks (see the collective rule in ``loop``).
        counts = owned_site_counts(lat, layout.bounds, layout.offsets[1])
        self.event_limit, capacity = event_room(int(counts[rank]) if lat.has_interface else 0, self.buffer_events)
        self.state = State(st, layout, self.dtype, event_capacity=capacity)
        self.release()
        self.plan = build_plan(layout, self.dtype, self.comm, st.shared_memory)
        self.sched = L.Schedule(tasks=layout.tasks, ptr=task_ranges(layout.tasks))
        drift = layout.reach.drift if layout.reach is not None else None
        self.params = self.params._replace(shift=drift.shift if drift is not None else 0)
        nsites = max(self.state.owned_sites().stop - self.state.owned_sites().start, 0)
        cap = self._buffer_frames if self._buffer_frames > 0 else frame_buffer(int(counts.max()), st.n_frames)
        self.buffer_frames = cap = int(min(cap, st.n_frames))
        ndrive = len(self.state.drive.force)
        cursor = self.frames.cursor if self.frames is not None else np.array([0, 0, -1], np.int64)
        self.frames = L.Frames(intact=np.zeros((cap, nsites), np.uint8), partner=np.zeros((cap, nsites), np.int32),
                               ux=np.zeros((cap, nsites)), uy=np.zeros((cap, nsites)), sxy=np.zeros((cap, nsites)),
                               syy=np.zeros((cap, nsites)), fx=np.zeros((cap, nsites)),
                               fdrive=np.zeros((cap, ndrive)), energy=np.zeros((cap, 5, bg.N_TERMS)),
                               step=np.zeros(cap, np.int64), cursor=cursor)
        self.budget = self._budget(st.damping.force_factor(st.dt))
        if drift is not None:
            q = L.DRIFT_QUANTA
            h = self.diag.halo
            h[L.H_LIMIT:L.H_LIMIT + 4] = np.round(np.array(drift.edges) * q).astype(np.int64)
            h[L.H_MARGIN:L.H_MARGIN + 4] = np.ceil(np.array(drift.skin) * q / 2).astype(np.int64)

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
        kernel cache compiles the loop and the others then load it; meanwhile another rank compiles the
        frames' kernels (which the loop types last) and those the loop does not call, the exact sums of frames
        and budget and the snapshots' stresses (``engine.compile``); returns how it went (``FirstCall``).
        Collective."""
        from .compile import first_call
        self._phase("compile")

        def side():
            from ..parallel.exact_sum import warm
            s = self.state
            L._record.compile(L.record_signature(s.levels, self.sched, s.K, self.params, s.iface, s.drive,
                                                 self.frames, self.diag, self.budget))
            warm()
            if self.snapshots_total:
                self.state.node_fields(self.n)
        return first_call(self.comm, lambda: self.advance(self.n), side)

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
            self.hold.read(self)
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
                         st.n_drive_start if self.n < st.n_drive_start else end,
                         self.hold.next_read(self.n) or end)
            if self.drive_clock is None and self.n >= st.n_drive_start:
                self.drive_clock = (time.monotonic(), time.process_time(), self.n)
            self._phase("loop")
            why = self.advance(target)
            if why in (L.FRAMES_FULL, L.EVENTS_FULL):
                self._flush(writer)
                continue
            if why == L.REBUILD:
                self._phase("rebuild")
                follow.rebuild(self, writer)
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
        """What the writer (``io.output.Output``) needs of this run, as a frozen ``RunSpec``: the node datasets'
        slices of this rank's slab of no drift (``io_placement``, one contiguous range of global ids), and the
        frames' sites and driven nodes of the slab it computes on (``output_sites``)."""
        from ..io.output import RunSpec
        lat, io, r = self.setup.lattice, self.io_placement, self.rank
        c0, c1 = int(io.bounds[r]), int(io.bounds[r + 1])
        sites = block_columns(lat, io, r, TOP) if lat.has_interface else (0, 0)
        return RunSpec(setup=self.setup, rank=r, size=self.size, col_range=(c0, c1), owned_sites=tuple(sites),
                       node0=int(lat.col_start[c0]), site0=sites[0] - lat.top.col0 if lat.has_interface else 0,
                       driven_gid=self.state.driven_gid, frames_total=self.frames_total,
                       snapshots_total=self.snapshots_total, buffer_frames=self.buffer_frames,
                       events_written=self.events_written, frame_site0=self.output_sites()[0])

    def output_sites(self) -> tuple:
        """(first global site of this rank's interface frames, global ids of its driven nodes): where the frames
        and drive forces it records belong, which change when the slabs follow the drift."""
        s, lat = self.state, self.setup.lattice
        return (s.site0() if lat.has_interface else 0), s.driven_gid

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
            held = None if self.hold.step is None else self.hold.step - self.setup.n_drive_start
            writer.interface_frames(base, count, fr, self.frame_time(fr.step[:count]), self.budget_frames(count),
                                    held=held)
        fr.cursor[L.C_BASE] += count
        fr.cursor[L.C_COUNT] = 0
        ev = self.state.iface.events
        m = int(ev.count[0])
        if writer is not None:
            nds = self.setup.n_drive_start
            fields = {name: getattr(ev, name)[:m] for name in ev._fields if name != "count"}
            fields["step"] = fields["step"] - nds
            self.events_written = writer.interface_events(self.events_written, fields, self.drive_time)
        ev.count[0] = 0

    # ----------------------------------------------------------- checkpoints --
    def checkpoint_table(self) -> np.ndarray:
        """Every rank's checkpoint slab, [ranks, 4]: node range [first, end), site range [first, end)
        (``io.checkpoint.slab_table``, from the slab bounds every rank holds)."""
        from ..io.checkpoint import slab_table
        return slab_table(self.setup.lattice, self.io_placement.bounds)

    def slab_ranges(self) -> tuple[tuple[int, int], tuple[int, int]]:
        """(global node ids [first, end), interface sites [first, end)) this rank owns: a checkpoint's rows
        it writes and reads."""
        row = self.checkpoint_table()[self.rank]
        return (int(row[0]), int(row[1])), (int(row[2]), int(row[3]))

    def checkpoint_slab(self):
        """This rank's share of a checkpoint (``io.checkpoint.Slab``): its OWNED nodes and sites of the slabs
        of no drift, in global order, each dataset in its checkpoint dtype (the state's float type bitwise)."""
        from ..io.checkpoint import Slab
        s = self.state
        nodes, sites = self.slab_ranges()
        # Each array is made once, in place: the slab is the only copy of the state this rank holds.
        a = {"u": s.owned_u(self.n, s.dtype), "u_prev": s.owned_u(self.n - 1, s.dtype),
             "drive0": np.zeros(s.n_owned, s.dtype), "drive_force": np.zeros(s.n_owned, s.dtype)}
        top = s.own_block == TOP
        a["drive0"][top] = s.drive.drive0[s.own_prow[top], s.own_j[top]]
        a["drive_force"][np.searchsorted(s.gid, s.driven_gid)] = s.drive.force
        bonds = s.owned_bonds() if self.setup.lattice.has_interface else \
            {name: np.zeros(0, s.dtype) for name in BONDS.checkpoint}
        if self._followed():
            # The slabs followed the drift: the state goes to the slabs of no drift, the checkpoint's slabs.
            got = self._to_io(a, bonds)
            a, bonds = got["nodes"][2], got["sites"][2]
        assert len(a["u"]) == nodes[1] - nodes[0]
        for name, row in bonds.items():
            a[name] = row.astype(BONDS.dtypes[name] or s.dtype, copy=False)
        return Slab(nodes, sites, a)

    def _followed(self) -> bool:
        """The slabs followed the drift away from those of no drift, which the files are written in."""
        here = follow.placement(self.layout)
        return self.size > 1 and not (np.array_equal(here.bounds, self.io_placement.bounds) and
                                      tuple(here.offsets) == tuple(self.io_placement.offsets))

    def _to_io(self, nodes: dict, sites: dict) -> dict:
        """Collective: columns by OWNED node (``nodes``) and by OWNED site (``sites``) sent to the ranks that
        hold them in the slabs of no drift (``parallel.migrate``), in global order there."""
        s = self.state
        n = self.state.owned_sites()
        site = np.arange(n.stop - n.start, dtype=np.int64) + (s.site0() if self.setup.lattice.has_interface else 0)
        return redistribute(self.comm, self.setup.lattice, follow.placement(self.layout), self.io_placement,
                            {"nodes": (NODES, s.gid, nodes), "sites": (SITES, site, sites)})

    def restore(self, slab, attrs: dict):
        """Continue from a checkpoint: the state at its step, the output cursor after what it wrote.

        ``slab`` holds this rank's OWNED nodes and sites (``io.checkpoint.read`` of ``slab_ranges``);
        the halo exchange then fills the HALO copies (collective)."""
        self._phase("restore")
        s, st = self.state, self.setup
        if (tuple(slab.nodes), tuple(slab.sites)) != self.slab_ranges():
            raise ValueError(f"restore: a slab of nodes {slab.nodes}, sites {slab.sites}; this rank owns "
                             f"{self.slab_ranges()}")
        self.n = n = int(attrs["step"])
        a = slab.arrays
        s.set_owned_u(n, a["u"])
        s.set_owned_u(n - 1, a["u_prev"])
        top = s.own_block == TOP
        s.drive.drive0[s.own_prow[top], s.own_j[top]] = a["drive0"][top]
        s.drive.force[:] = a["drive_force"][s.driven_gid - slab.nodes[0]]
        if st.lattice.has_interface:
            s.set_owned_bonds({name: a[name] for name in BONDS.checkpoint})
        self.refill_halos()
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
        self._energy_restore(attrs, a["u_prev"][s.driven_gid - slab.nodes[0]])
        self.hold.restore(self, attrs)
        follow.resume(self, attrs)          # the restored slabs of no drift follow the checkpoint's drift

    def refill_halos(self):
        """Fill every HALO copy from the rank that owns it, at both Verlet levels u(n) and u(n - 1) (a rule
        may read u(n - 1) of HALO sites: the slip velocity), with the bond rows that travel; collective.
        After a restore, which sets OWNED values only."""
        if self.comm is None:
            return
        from ..parallel.halo_mpi import mpi_complete, mpi_post
        s = self.state
        for level in (self.n - 1, self.n):
            bx, by, tx, ty = s.level(level)
            mpi_post(self.plan, bx, by, tx, ty, s.iface.bonds)
            mpi_complete(self.plan, bx, by, tx, ty, s.iface.bonds)

    # ---------------------------------------------------------- energy budget --
    def budget_frames(self, count: int) -> dict | None:
        """Rank 0: the energy budget of the ``count`` frames held (m c_r^2), since the drive started: the
        sources (contract ``ENERGY_SOURCES``: work_drive, work_normal, formed, contact_switched) equal the
        sinks (``ENERGY_SINKS``: elastic, kinetic, contact, damping, broken) plus the residual (contract
        ``ENERGY_DATASETS``); collective.  The damping is summed in the loop with ``output.energy =
        "checked"`` and the body drag, else it is the balance and the residual NaN.  The state's terms at the drive's start come from its frame
        (or from the checkpoint a run continues); without them (a checkpoint that predates the budget)
        they read NaN."""
        fr = self.frames
        # Each frame's terms as every rank's parts (a pair and the quanta's exact parts: [frame, part, term]),
        # summed over parts and ranks exactly and rounded once (``parallel.exact_sum``): the correctly
        # rounded sum, the same bits on any rank count (and those math.fsum of every part would give).
        got = exact_sums(self.comm, [fr.energy[:count].transpose(0, 2, 1)], root=0)
        if got is None:
            return None
        tot = got[0]                                              # [frame, term]
        if self.energy_base is None and fr.cursor[L.C_BASE] == 0 and fr.step[0] == self.setup.n_drive_start:
            self.energy_base = tot[0, list(bg.STATE)].copy()
        base = self.energy_base if self.energy_base is not None else np.full(len(bg.STATE), np.nan)
        e = 1.0 / self.setup.material.c_r ** 2
        change = {term: (tot[:, term] - base[k]) * e for k, term in enumerate(bg.STATE) if term != bg.LOAD_Y}
        out = {"work_drive": tot[:, bg.W_DRIVE] * e, "damping": tot[:, bg.DAMPING] * e,
               "broken": tot[:, bg.BROKEN] * e, "formed": tot[:, bg.FORMED] * e,
               "kinetic": change[bg.KINETIC], "elastic": change[bg.ELASTIC],
               "work_normal": 0.5 * self.params.fext * (tot[:, bg.LOAD_Y] - base[bg.STATE.index(bg.LOAD_Y)]) * e,
               "contact": change[bg.CONTACT], "contact_switched": tot[:, bg.SWITCHED] * e,
               "softening": tot[:, bg.SOFTENED] * e, "friction": tot[:, bg.FRICTION] * e}
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
        # Over the ranks: each term's pairs summed exactly, rounded once (hi) with what that left (lo), as
        # math.fsum of every pair would give them; the quanta are integers, their sum is exact.
        (hi, lo), = exact_sums(self.comm, [mine.T], remainder=True)
        if self.comm is not None:
            quanta = self.comm.allreduce(quanta, op=lambda a, c: [x + y for x, y in zip(a, c)])
        base = self.energy_base if self.energy_base is not None else np.full(len(bg.STATE), np.nan)
        if self.comm is not None:          # rank 0 holds the base (the drive's first frame, or a checkpoint's)
            base = self.comm.bcast(base, root=0)
        return {"energy_totals": np.array([hi, lo]), "energy_base": np.asarray(base, np.float64),
                "energy_quanta": np.array([[t >> bg.WORD, t & ((1 << bg.WORD) - 1)] for t in quanta], np.int64)}

    def _energy_restore(self, attrs: dict, driven_u_prev: np.ndarray):
        """Continue the budget from a checkpoint: rank 0 carries the totals, every rank its slots' u(n-1)
        (``driven_u_prev``: [slots, 2], the driven nodes' rows of the checkpoint)."""
        b = self.budget
        tot = attrs.get("energy_totals")
        b.base[:] = 0.0
        b.acc[:] = 0
        if self.rank == 0:
            b.base[:] = np.nan if tot is None else self._later_terms(tot, range(bg.N_TERMS))
            if tot is not None:
                b.acc[:] = np.asarray(attrs["energy_quanta"], np.int64)
            # None where not known yet (a checkpoint before the drive's start): the drive's first frame gives it.
            base = attrs.get("energy_base")
            known = base is not None and not np.isnan(base).all()
            self.energy_base = self._later_terms(np.asarray(base)[None], bg.STATE)[0] if known else None
        b.prev[:] = driven_u_prev.T

    def _later_terms(self, values, terms) -> np.ndarray:
        """A checkpoint's budget terms ([rows, terms]) padded to the terms ``terms`` (their indices, in order): a
        checkpoint written before a term existed carries none.  The contact's terms are 0 without a contact
        and unknown (NaN) with one; the weakening's 0 (a checkpoint before it had no weakening)."""
        values = np.asarray(values, np.float64)
        terms = list(terms)[values.shape[1]:]
        fill = [np.nan if self.setup.law.contact and t in (bg.CONTACT, bg.SWITCHED) else 0.0 for t in terms]
        return np.concatenate([values, np.tile(np.asarray(fill, np.float64), (values.shape[0], 1))], axis=1)

    def checkpoint_attrs(self) -> dict:
        """The scalar part of a checkpoint, collective (the event counters are summed over the ranks)."""
        st = self.setup
        counters = self.counters.copy()
        if self.comm is not None:
            counters = self.comm.allreduce(counters)
        return {**self._energy_checkpoint(), **self.hold.attrs(), "step": self.n, "time_lcr": st.to_lcr((self.n - st.n_drive_start) * st.dt),
                "frames_written": self.frames_written, "last_frame_step": self.last_frame_step,
                "events_written": self.events_written,
                "snapshots_written": self.snapshots_written, "counters": counters,
                "omega_max": st.omega_max, "omega_method": st.omega_method, "dt": st.dt, "n_ranks": self.size,
                "precision": self.dtype.name, **follow.checkpoint_attrs(self)}

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
        partner = self.state.owned_partner()
        far = self._far_ends(pos, partner)                # read where the state is, before any move
        if self._followed():
            got = self._to_io({"pos": pos, "vel": vel, "sig": sig}, {"partner": partner, "far": far})
            cols, sites = got["nodes"][2], got["sites"][2]
            pos, vel, sig, partner, far = cols["pos"], cols["vel"], cols["sig"], sites["partner"], sites["far"]
        writer.snapshot(j, t, pos, vel, sig, partner, far)

    def _far_ends(self, pos: np.ndarray, partner: np.ndarray) -> np.ndarray:
        """(sites, 3) where the far end of each OWNED site's interface cell stands at step n (a): its bond's
        substrate node (read from this rank's arrays, which hold every node a bond of its sites reaches,
        HALO copies included), or its own top node while broken or bonded to a rigid substrate.  The same
        sum as ``State.node_fields``'s reference + u, so the same bits as that node's own point."""
        s, lat = self.state, self.setup.lattice
        if not lat.has_interface:
            return np.zeros((0, 3))
        top = (s.own_block == TOP) & (s.own_row == 0)                 # the sites' nodes, in site order
        out = pos[top].copy()
        bonded = np.flatnonzero(partner >= 0) if not lat.rigid else np.zeros(0, np.int64)
        if len(bonded):
            bx, by, _, _ = s.level(self.n)
            g = s.iface.geom
            col = partner[bonded]
            row = lat.bottom.rows - 1
            ux = bx[g.brow, col - g.bbase].astype(np.float64)
            uy = by[g.brow, col - g.bbase].astype(np.float64)
            out[bonded, 0] = (col + lat.bottom.offset(row)) + ux
            out[bonded, 1] = (lat.bottom.y0 + row * ROW_HEIGHT) + uy
        return out

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
            if self.params.follow:
                grow = max(st.skin[1] * 2, 2 * slip)
                raise SlipReachError(
                    f"interface slip reached {slip:.3g} a (the block relative to the substrate) at step {step} "
                    f"(t = {t:.4g} l/c_r): {what}: the slip grew faster between two agreements of the ranks than "
                    f"the halos' skin of {st.skin[1]:.3g} a allows; rerun with --set interface.halo_skin={grow:.3g}")
            raise SlipReachError(
                f"interface slip reached {slip:.3g} a (the block relative to the substrate) at step {step} "
                f"(t = {t:.4g} l/c_r): {what}, beyond "
                f"interface.slip_reach = {st.slip_reach:.3g} a that the MPI halo covers; rerun with --set "
                f"interface.slip_reach={max(2 * slip, st.slip_reach + 2):.3g}, or 0 to let the halos follow it")
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
        if lat.has_interface and site_row and st.law.contact > 0:
            # Seen on study 5 once the contact slid whole: the contact's switches feed a vibration as fast as
            # the damping takes it; a smaller time.safety only raises the speed this check trips at.
            cause = ("a contact that slides (interface.contact), whose switches feed the interface's vibration "
                     "at any time step (a smaller time.safety only hides it: docs/guide/interfaces.md, 'Friction "
                     "on the contact'); or " + cause)
        if f[L.L_BITS] & L.FLAG_NONFINITE:
            return (f"state became non-finite at step {step} (t = {t:.4g} l/c_r from drive start) at {node}; "
                    f"likely cause: {cause}")
        return (f"state grew without bound: at step {step} (t = {t:.4g} l/c_r from drive start) the {node} "
                f"moved {f[L.L_VALUE] / 1e6:.3g} a in one step (faster than any wave of the lattice); likely cause: "
                f"{cause}; output written so far is kept")
