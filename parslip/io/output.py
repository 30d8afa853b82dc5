"""The one HDF5 file a run writes: the interface record, snapshots, provenance.

Responsible for writing the output contract of ``io.contract`` (read its
docstring for the datasets and their units; ``io.mesh`` for where the
snapshots go).

Sites are ordered by x.  Every dataset has a fixed size known at the start,
and each rank's share of it is one contiguous block (global ids run column
by column), or two (a snapshot's nodes and its sites' far ends).  With an
MPI-enabled h5py every rank writes its own blocks through the ``mpio``
driver, each dataset in one collective write (HDF5 then merges the ranks'
blocks into large contiguous file accesses); otherwise rank 0 writes its own
blocks, then asks every other rank for its blocks in turn and writes them
(``parallel.pieces.stream_to_root``), so it never holds more than its own
and one other rank's share.  The sums over every rank (friction and drive
forces, the energy budget) are exact reductions (``parallel.exact_sum``),
and the bond events are placed in their global order by histograms over
steps (``parallel.pieces.place_by_step``): no rank gathers the others'
values.  Either way the file is identical for any rank count.
"""
from __future__ import annotations

import os
import sys
import time

from dataclasses import dataclass

import h5py
import numpy as np
from h5py import h5fd, h5p, h5s

from .. import hooks
from ..version import __version__
from ..errors import ConfigError, WriteError
from ..model.lattice import BOTTOM, TOP
from ..parallel.exact_sum import exact_sums
from ..parallel.pieces import place_by_step, stream_to_root
from .contract import (ENERGY, ENERGY_DATASETS, EVENT_DATASETS, EVENTS, FAR_NODE, FRAME_FIELDS,
                       INTERFACE_DATASETS, PER_FRAME_1D, SITE_DATASETS, SNAPSHOTS, STATUS, TIMING_PREFIX, VTKHDF,
                       put_status, status_value)
from .mesh import PER_STEP, SHARED, Mesh, Share, per_step_cells, snapshot_pieces, static_pieces
from .scenefile import to_toml

# Chunks.  A write that covers whole chunks goes straight to the file; one that covers part of a chunk
# goes through HDF5's chunk cache (1 MiB per dataset), or, for a chunk larger than the cache, reads the chunk
# back first.  So: an interface dataset's chunk holds one frame buffer's worth of frames (the blocks the
# loop hands over, aligned to it), and a snapshot dataset's chunk one snapshot's rows, at most CHUNK_BYTES
# (measured on 100 sites: 1.7 against 2.9 us per frame with 655-frame chunks; a 1,000-node snapshot's
# Points written into 65,536-row chunks read 1.5 MB back each time).
CHUNK_BYTES = 1 << 20
# The gathering writer's messages to rank 0: at most this many bytes each (``parallel.pieces.stream_to_root``),
# so rank 0 holds its own share and one message, whatever the rank count or another rank's share.
STREAM_BYTES = 1 << 20
EVENT_CHUNK = 1 << 14            # events per chunk of /interface/events/* (grown at each flush that has some)
MAX_FRAME_CHUNK_BYTES = 4 << 20
# The file is flushed (metadata and all) at least this often while frames are written (s), at each
# checkpoint and at the end: a full disk shows within this long, and without a flush per block of frames.
FLUSH_S = 10.0
_UNCLOSABLE: list = []          # files whose close failed, and their objects (see ``Output.close``)


def hdf5_mode(size: int, comm=None) -> str:
    # With a communicator, an MPI-enabled h5py writes through mpio on any rank count, one included.
    return "mpio" if (size > 1 or comm is not None) and h5py.get_config().mpi else "gather"


def _bulk_cells(lat, c0: int, c1: int, chunk: int = 512) -> np.ndarray:
    """[cells, 2] global ids of the bulk bonds 0..2 (each bond once) of the nodes in columns [c0, c1).

    Built a few hundred columns at a time, so the temporaries stay small whatever the lattice."""
    parts = []
    for a in range(c0, c1, chunk):
        nodes = lat.nodes_in_columns(a, min(a + chunk, c1))
        nbr = lat.neighbour_gids(nodes)[:, :3]
        has = nbr >= 0
        parts.append(np.stack([np.repeat(nodes["gid"][:, None], 3, 1)[has], nbr[has]], axis=1))
    return np.concatenate(parts).astype(np.int64) if parts else np.zeros((0, 2), np.int64)


def _early():
    """Dataset creation: every chunk allocated when the dataset is (or grows), never filled.

    Writes of frames and snapshots then change no metadata, so a file flushed
    at a checkpoint stays readable if the process is killed afterwards, and a
    restart can append to it.
    """
    dcpl = h5py.h5p.create(h5py.h5p.DATASET_CREATE)
    dcpl.set_alloc_time(h5py.h5d.ALLOC_TIME_EARLY)
    dcpl.set_fill_time(h5py.h5d.FILL_TIME_NEVER)
    return dcpl


@dataclass(frozen=True)
class RunSpec:
    """What the writer needs of a run, handed over by the engine when it opens the output (the engine's
    ``Simulation.output_spec``), so the writer reads no engine object.

    setup             the derived set-up (``scene.derive.Setup``): lattice, scene, dt, frame and snapshot steps
    rank, size        this rank and the rank count
    col_range         (first, end) global columns of this rank's slab
    owned_sites       (first, end) global interface sites this rank owns
    node0, site0      the first OWNED global node id, and the first global site of this rank's interface record
    driven_gid        global ids of this rank's driven nodes, in the order of its drive forces
    frames_total      interface frames in the file once the run ends (an earlier run's included)
    snapshots_total   snapshots in the file once the run ends
    buffer_frames     frames the engine holds between flushes (the frame datasets' chunk rows)
    events_written    bond events in the file already (a restart's)
    frame_site0       the first global site of this rank's interface frames: its slab's sites as it computes
                      them, which differ from the node datasets' slab once the slabs follow the drift
                      (``follow`` updates it and driven_gid as they move)
    """
    setup: object
    rank: int
    size: int
    col_range: tuple
    owned_sites: tuple
    node0: int
    site0: int
    driven_gid: np.ndarray
    frames_total: int
    snapshots_total: int
    buffer_frames: int
    events_written: int
    frame_site0: int = 0


class Output:
    """Writes the contract above; every method is collective over the ranks.

    A write that fails (no space, a quota, a folder that vanished) does not
    raise on the failing rank alone: every public write ends by agreeing on
    errors (``_agree_write``), so all ranks raise the same ``WriteError`` at
    the same call and none is left waiting in a collective.
    """

    def __init__(self, path: str, spec: RunSpec, comm=None, provenance: dict | None = None,
                 resume: str | None = None):
        """Create ``path`` for a new run, or with ``resume`` (the checkpoint's run id) reopen it to append."""
        self.spec, self.comm, self.path = spec, comm, path
        self._handles = {}
        self._error = None                 # the first failed write on this rank: (what, OSError text)
        self._flushed = time.monotonic()   # rank 0's clock: when the file was last flushed
        self.frames_safe = 0               # frames on disk: frames_written at the last successful flush
        self._frames_set = 0               # frames_written as last set (on disk at the next flush)
        self._held = False                 # the test hook hold_at_frame has held this run once
        self._status_at = None             # where /status's bytes are in the file (``_status_on_disk``)
        st, lat = spec.setup, spec.setup.lattice
        self.rank = spec.rank
        self.size = spec.size
        self.mode = hdf5_mode(self.size, comm)
        self.root = self.rank == 0
        self.f = self._open(path, comm, "r+" if resume else "w")

        # My slices of the global arrays: OWNED nodes are a contiguous range of global ids, and so are my
        # columns' bulk bonds in the global order of bonds.
        self.node0, self.site0 = spec.node0, spec.site0
        self.frame_site0 = spec.frame_site0
        c0, c1 = spec.col_range
        bulk = _bulk_cells(lat, c0, c1)
        nb = len(bulk)
        self.cell0 = self._exscan(nb)
        self.n_nodes, self.n_sites = lat.n_nodes, lat.n_top_sites
        lo, hi = spec.owned_sites
        self.top_gid = lat.gid(TOP, 0, np.arange(lo, hi)).astype(np.int64)
        self.driven_gid = spec.driven_gid
        self.fn = float(st.scene["load.FN"])
        # A bond to a rigid substrate has no substrate node: drawn, like a broken bond, as a point-line.
        self.bottom_gid_of_site = ((lambda q: np.full(np.shape(q), -1, np.int64)) if lat.rigid else
                                   (lambda q: lat.gid(BOTTOM, lat.bottom.rows - 1, q)))
        self._dxpl = None
        if self.mode == "mpio":            # every dataset write collective (``_write_pieces``)
            self._dxpl = h5p.create(h5p.DATASET_XFER)
            self._dxpl.set_dxpl_mpio(h5fd.MPIO_COLLECTIVE)
        self._catch_unraisable()
        self._old_snapshots = 0            # snapshot slots the file held before a restart grew it
        snapshots = bool(self.spec.snapshots_total) and st.scene["output.fields"] != "interface"
        # A restart goes on in the layout its file has (``io.mesh``); a new file shares its mesh.
        layout = self._file_layout() if resume and snapshots else SHARED
        self.mesh = Mesh(lat.n_nodes, lat.n_top_sites, self._allreduce(nb), layout)
        self.share = Share(node0=self.node0, n_nodes=int(lat.col_start[c1] - lat.col_start[c0]), cell0=self.cell0,
                           n_bulk=nb, site0=self.site0, top_gid=self.top_gid, last=self.rank == self.size - 1)
        # The per-step layout writes its bonds with every snapshot; the shared one once, below.
        self.bulk_cells = bulk if layout == PER_STEP else None
        if resume:
            self._resume(st, resume)
        else:
            self._write("(creating the datasets)", lambda: self._create(st, provenance or {}))
        # A file from before the energy budget has no /energy (under mpio every rank sees the same file).
        self._has_energy = self.f is not None and ENERGY in self.f
        try:
            if snapshots and not resume:
                self._agree_write()        # before the collective writes of the stored mesh
                self._write_pieces(static_pieces(self.mesh, self.share, bulk))
            del bulk
            self.flush()
        except WriteError:
            self.close(status=f"failed: cannot write {path}")
            raise

    def _catch_unraisable(self):
        """HDF5 writes metadata when h5py objects are freed; on a full disk that fails inside a destructor,
        where Python can only print a traceback.  While this file is open such failures are kept as this
        rank's write error instead (one line, agreed at the next write) and nothing is printed."""
        prev = sys.unraisablehook

        def hook(u):
            if isinstance(u.exc_value, (OSError, RuntimeError)) and "h5py" in str(u.object):
                if self._error is None:
                    self._error = ("(metadata)", _hdf5_error_line(u.exc_value))
                return
            prev(u)
        self._prev_unraisable = prev
        sys.unraisablehook = hook
    # ------------------------------------------------------------ plumbing --
    def _open(self, path, comm, how):
        """Open for writing (``how`` "w" or "r+"); a file that cannot be opened is bad input on every rank."""
        err, f = None, None
        try:
            if self.mode == "mpio":
                f = h5py.File(path, how, driver="mpio", comm=comm)
            elif self.root:
                f = h5py.File(path, how)
        except OSError as e:
            err = f"--out {path!r}: cannot open for writing ({e.__class__.__name__}: {e}); " \
                  "accepted: a writable path not held open by another program"
        self._agree(err, f)
        return f

    def _agree(self, err, f=None):
        """Raise the first rank's error on every rank (closing the file), so no rank waits for another."""
        if self.size > 1:
            errs = [m for m in self.comm.allgather(err) if m]
            err = errs[0] if errs else None
        if err:
            if f is not None:
                f.close()
            raise ConfigError(err)

    def _exscan(self, n: int) -> int:
        """The sum of ``n`` over the ranks below this one (a scan, no gather)."""
        if self.comm is None or self.size == 1:
            return 0
        below = self.comm.exscan(int(n))
        return int(below) if self.rank else 0

    def _allreduce(self, n: int) -> int:
        return int(n) if self.comm is None or self.size == 1 else int(self.comm.allreduce(int(n)))

    def _file_layout(self) -> str:
        """The snapshot layout of the file being continued: rank 0 reads it (in gather mode it alone holds
        the file), every rank learns it."""
        layout = None
        if self.f is not None:
            layout = SHARED if SNAPSHOTS in self.f or VTKHDF not in self.f else PER_STEP
        return layout if self.size == 1 or self.mode == "mpio" else self.comm.bcast(layout, root=0)

    def _ds(self, name):
        """Dataset ``name``, looked up once: a snapshot writes a dozen of them, and h5py's path lookup
        costs about as much as writing a small one."""
        ds = self._handles.get(name)
        if ds is None:
            ds = self._handles[name] = self.f[name]
        return ds

    def _write(self, what, fn):
        """Run one write; keep the first failure instead of raising it on this rank alone (h5py raises
        OSError, or RuntimeError when HDF5 fails to flush its metadata)."""
        if self._error is not None:
            return
        try:
            fn()
        except (OSError, RuntimeError) as e:
            self._error = (what, _hdf5_error_line(e))

    def _write_pieces(self, pieces: list):
        """Write this rank's pieces [(dataset, rows, values)]: rows a tuple of slices (a block), an increasing
        int array (points of a 1-D dataset) or None (nothing from this rank); a dataset's pieces listed
        together, in increasing order.  Collective.

        mpio: one collective write per dataset (its pieces one selection), so every rank lists the same
        datasets in the same order; a rank whose earlier write failed still takes part, with nothing.
        gather: rank 0 writes its own pieces, then each other rank's in turn, in messages of at most
        STREAM_BYTES (``parallel.pieces.stream_to_root``)."""
        if self.mode == "mpio":
            for name, group in _by_dataset(pieces):
                if self._error is not None:
                    group = []
                try:
                    _h5_write(self._ds(name), group, self._dxpl)
                except (OSError, RuntimeError) as e:
                    if self._error is None:
                        self._error = (name, _hdf5_error_line(e))
            return

        def take(piece):
            name, rows, values = piece
            self._write(name, lambda: _h5_write(self._ds(name), [(rows, values)]))
        mine = [q for p in pieces if p[1] is not None for q in _split(*p, STREAM_BYTES)]
        stream_to_root(self.comm if self.size > 1 else None, mine, take, lambda p: np.asarray(p[2]).nbytes,
                       STREAM_BYTES)

    def _write_root(self, pieces: list):
        """Rank 0 writes pieces only it holds (the per-frame series, the snapshots' times): independently under
        mpio (no other rank has a part), directly in gather mode.  Not collective."""
        if self.root:
            for name, rows, values in pieces:
                self._write(name, lambda: _h5_write(self._ds(name), [(rows, values)]))

    def _agree_write(self, flag: bool = False) -> bool:
        """Collective: raise ``WriteError`` on every rank if a write failed on any; else return ``flag`` as
        rank 0 has it (a decision that rides along).

        Every call that is collective under mpio (attributes, resize, flush, close) comes right after an
        agreement, so a rank whose write failed never skips one that the others enter."""
        err = self._error
        if self.size > 1:
            got = self.comm.allgather((err, flag))
            errs = [e for e, _ in got if e]
            err = errs[0] if errs else None
            flag = got[0][1]
        if err:
            self._error = err
            what, text = err
            # What the file holds is what its last successful flush put on disk: HDF5 keeps the rest,
            # frames_written among it, in memory until the next flush, which a full disk refuses.
            safe = (f"frames 0 to {self.frames_safe - 1} of the interface record reached the disk before"
                    if self.frames_safe else "no frame of the interface record reached the disk")
            where = f"dataset /{what}" if not what.startswith("(") else what.strip("()")
            raise WriteError(f"cannot write {self.path} ({text}; {where}); {safe}", path=self.path,
                             frames_safe=self.frames_safe)
        return flag

    def _create(self, st, prov):
        """Create every dataset (collective under mpio), sized for this run and growable for a restart."""
        f = self.f
        if f is None:
            return
        nf, ns, N = self.spec.frames_total, self.n_sites, self.n_nodes
        a = f.attrs
        a["scene"] = to_toml(st.scene)
        for k, v in prov.items():
            a[k] = v
        a["parslip_version"] = __version__
        a.setdefault("git_commit", "unknown")
        put_status(f, "running")
        self._status_at = f[STATUS].id.get_offset()
        a["hdf5_mode"] = self.mode
        a["n_ranks"] = self.size
        a["n_nodes"] = N
        a["n_steps"] = st.n_steps
        a["n_drive_steps"] = st.n_drive
        a["dt"] = st.dt
        a["dt_limit"] = st.dt_limit
        a["omega_max"] = st.omega_max
        a["omega_method"] = st.omega_method
        a["precision"] = st.precision
        a["substrate"] = st.lattice.substrate
        a["c_s"], a["c_l"], a["c_r"] = st.material.c_s, st.material.c_l, st.material.c_r
        a["c_surface_born"] = st.material.c_surface_born
        a["kn_top"], a["kt_top"] = st.material.kn_top, st.material.kt_top
        a["l"] = st.l
        a["units"] = ("internal: a = 1, node mass = 1, velocity unit " + st.material.velocity_unit +
                      "; /interface: lengths in l, time in l/c_r; VTKHDF: positions in a, "
                      "velocity in internal units, stress in rho c_r^2, step times in l/c_r")
        g = self._handles["interface"] = f.create_group("interface")
        g.attrs["frame_every_steps"] = st.frame_every
        g.attrs["frames_written"] = 0
        rows = max(1, min(max(nf, 1), self.spec.buffer_frames, MAX_FRAME_CHUNK_BYTES // (8 * max(ns, 1))))
        for name, (dt_, per_frame, unit) in INTERFACE_DATASETS.items():
            if per_frame and ns == 0:     # a free block: no interface sites, nothing to grow
                ds = g.create_dataset(name, shape=(nf, 0), dtype=dt_)
            elif per_frame:
                ds = g.create_dataset(name, shape=(nf, ns), maxshape=(None, ns), dtype=dt_,
                                      chunks=(rows, ns), dcpl=_early())
            elif name in PER_FRAME_1D:
                ds = g.create_dataset(name, shape=(nf,), maxshape=(None,), dtype=dt_, chunks=(max(rows, 64),),
                                      dcpl=_early())
            else:
                ds = g.create_dataset(name, shape=(ns,), dtype=dt_)
            ds.attrs["units"] = unit
            # Every h5py object stays referenced until the file closes: a dataset freed earlier writes its
            # metadata in a destructor, where a full disk can only print tracebacks.
            self._handles[f"interface/{name}"] = ds
        if self.root:
            g["x"][...] = (np.arange(ns) + 0.5) / ns    # node s stands at the middle of its spacing
            values = st.law.site_values(ns)
            for name in SITE_DATASETS[1:]:          # after x: the bond table's rows written once per site
                g[name][...] = values[name]
        self._create_energy(nf, rows)
        ev = self._handles[f"interface/{EVENTS}"] = g.create_group(EVENTS)
        ev.attrs["events_written"] = 0
        ev.attrs["site_column0"] = int(st.lattice.top.col0)
        for name, (dt_, unit) in EVENT_DATASETS.items():
            ds = ev.create_dataset(name, shape=(0,), maxshape=(None,), dtype=dt_, chunks=(EVENT_CHUNK,))
            ds.attrs["units"] = unit
            self._handles[f"interface/{EVENTS}/{name}"] = ds
        if self.spec.snapshots_total == 0 or st.scene["output.fields"] == "interface":
            return          # no snapshots asked for: no empty VTKHDF group either
        self._create_snapshots(self.spec.snapshots_total)

    def _create_snapshots(self, S: int):
        """The /VTKHDF group and /snapshots for S snapshots (``io.mesh``), the steps' offsets written."""
        v = self._handles[VTKHDF] = self.f.create_group(VTKHDF)
        v.attrs["Version"] = np.array([2, 2], np.int64)
        v.attrs["Type"] = np.bytes_(b"UnstructuredGrid")
        far = self.f.create_group(SNAPSHOTS)
        far.attrs["units"] = "global node ids"
        for path, shape in self.mesh.shapes(S).items():
            if path == f"{VTKHDF}/Steps/Values":
                shape = (0,)              # grows with each snapshot: VTK's reader needs len(Values) == NSteps
            self._handles[path] = self.f.create_dataset(
                path, shape=shape, maxshape=(None,) + shape[1:], dtype=self.mesh.dtype(path),
                chunks=(self._chunk_rows(path, shape),) + shape[1:], dcpl=_early())
        self._handles[f"{SNAPSHOTS}/{FAR_NODE}"].attrs["meaning"] = (
            "per snapshot and interface site: the global id of the node at the far end of the site's interface "
            "cell (its bond's substrate node; its top node while broken or on a rigid substrate)")
        self._ds(f"{VTKHDF}/Steps").attrs["NSteps"] = np.int64(0)
        if self.root:
            for path, values in self.mesh.counts().items():
                self._ds(path)[:] = values
        self._step_constants(0, S)

    def _create_energy(self, nf: int, rows: int):
        """The /energy group: one value per frame of each budget term (``contract.ENERGY_DATASETS``)."""
        en = self._handles[ENERGY] = self.f.create_group(ENERGY)
        en.attrs["units"] = "m c_r^2"
        for name, meaning in ENERGY_DATASETS.items():
            ds = en.create_dataset(name, shape=(nf,), maxshape=(None,), dtype=np.float64, chunks=(max(rows, 64),),
                                   dcpl=_early())
            ds.attrs["units"] = "m c_r^2"
            ds.attrs["meaning"] = meaning
            self._handles[f"{ENERGY}/{name}"] = ds

    def _step_constants(self, k0: int, k1: int):
        """Per-step constants of snapshots k0..k1-1 (the ``Steps`` offsets; in the per-step layout also each
        step's part counts, cell offsets and types, one step at a time), written by rank 0 when the file is
        made or grows: a snapshot then writes its data only."""
        if not self.root or k1 <= k0:
            return
        k = np.arange(k0, k1, dtype=np.int64)
        for path, values in self.mesh.step_values(k).items():
            self._ds(path)[k0:k1] = values
        if self.mesh.layout == PER_STEP:
            for j in range(k0, k1):
                for path, rows, values in per_step_cells(self.mesh, j):
                    self._ds(path)[rows] = values

    def _chunk_rows(self, path: str, shape: tuple) -> int:
        """Rows of a snapshot dataset's chunk: one snapshot's rows (``Mesh.rows_per_chunk``), at most
        CHUNK_BYTES, at most the dataset."""
        width = int(np.prod(shape[1:])) * 8
        per = self.mesh.rows_per_chunk(path)
        return int(max(1, min(per, max(1, CHUNK_BYTES // width), max(shape[0], 1))))

    def _resume(self, st, run_id: str):
        """A restart: the file must be this run's; its datasets grow to what the rest of the run writes."""
        f = self.f
        err = None
        if f is not None and str(f.attrs.get("run_id", "")) != run_id:
            err = (f"--out {self.path!r}: belongs to another run than the checkpoint (run_id "
                   f"{f.attrs.get('run_id', '')!r}, checkpoint {run_id!r}); accepted: the output file the "
                   f"checkpointed run wrote")
        self._agree(err, f)
        if f is not None:
            g = f["interface"]
            nf = self.spec.frames_total
            for name, (_, per_frame, _) in INTERFACE_DATASETS.items():
                if (per_frame and self.n_sites) or name in PER_FRAME_1D:
                    if name in g:
                        g[name].resize(nf, axis=0)
            if ENERGY in f:
                for name, meaning in ENERGY_DATASETS.items():
                    if name not in f[ENERGY]:    # a file from before the term existed: NaN for its frames
                        old = f[ENERGY]["residual"]
                        ds = f[ENERGY].create_dataset(name, data=np.full(old.shape, np.nan), maxshape=(None,),
                                                      chunks=old.chunks)
                        ds.attrs["units"], ds.attrs["meaning"] = "m c_r^2", meaning
                    f[ENERGY][name].resize(nf, axis=0)
            if EVENTS in g:                  # events past the checkpoint's are written again from there
                for name, (dt_, unit) in EVENT_DATASETS.items():
                    if name not in g[EVENTS]:    # a file from before the field existed: NaN for its events
                        g[EVENTS].create_dataset(name, data=np.full(g[EVENTS]["step"].shape, np.nan, dt_),
                                                 maxshape=(None,), chunks=(EVENT_CHUNK,)).attrs["units"] = unit
                    g[EVENTS][name].resize(self.spec.events_written, axis=0)
                g[EVENTS].attrs["events_written"] = self.spec.events_written
            for name in SITE_DATASETS:       # a file from before the row existed: the values this run uses
                if name not in g:
                    g.create_dataset(name, data=st.law.site_values(self.n_sites)[name]).attrs["units"] = \
                        INTERFACE_DATASETS[name][2]
            if VTKHDF in f:
                old = self._old_snapshots = f[f"{VTKHDF}/Steps/PointOffsets"].shape[0]
                for path, shape in self.mesh.shapes(self.spec.snapshots_total).items():
                    if self.mesh.grows(path) and path != f"{VTKHDF}/Steps/Values":
                        f[path].resize(shape[0], axis=0)
                self._step_constants(old, self.spec.snapshots_total)
            put_status(f, "running")
            self._status_at = f[STATUS].id.get_offset()
            f.attrs["scene"] = to_toml(st.scene)
            f.attrs["n_ranks"] = self.size

    # --------------------------------------------------------------- writes --
    def interface_frames(self, k0, count, frames, times, energy=None, held=None):
        """Frames k0 .. k0 + count - 1 from the buffer ``frames`` (``engine.loop.Frames``) of my sites,
        recorded at ``times`` (l/c_r); with them the force sums of each frame (``forces``) and, from rank 0,
        their energy budget ``energy`` (``ENERGY_DATASETS``; None: not kept).  ``held``: the drive step from
        which the loader holds still (``drive.prestress``), None while it moves."""
        ns = frames.intact.shape[1]
        sl = (slice(k0, k0 + count), slice(self.frame_site0, self.frame_site0 + ns))
        self._test_hooks(k0 + count)
        sums = self.forces(frames.fx[:count], frames.fdrive[:count])
        self._agree_write()            # no rank enters the collective writes after a failure of its own
        self._write_pieces([(f"interface/{name}", sl, getattr(frames, name)[:count]) for name in FRAME_FIELDS])
        if self.root:                  # the per-frame series: rank 0 alone holds them
            st = self.spec.setup
            steps = frames.step[:count] - st.n_drive_start
            moved = steps if held is None else np.minimum(steps, held)
            per_frame = dict(sums, time=times, step=steps,
                             loader=moved * st.dt * st.v0 / st.l if st.drive.on else np.zeros(count))
            rows = (slice(k0, k0 + count),)
            pieces = [(f"interface/{name}", rows, values) for name, values in per_frame.items()]
            if energy is not None and self._has_energy:
                pieces += [(f"{ENERGY}/{name}", rows, values) for name, values in energy.items()]
            self._write_root(pieces)
        # Rank 0's clock decides whether to flush, and every rank learns it from the agreement below, since
        # under mpio the flush is collective.
        due = self.rank == 0 and time.monotonic() - self._flushed >= FLUSH_S
        due = self._agree_write(due)   # before the collective calls below: no rank may skip one alone
        if self.f is not None:
            self._write("interface", lambda: self._ds("interface").attrs.__setitem__("frames_written", k0 + count))
            if due:
                self._write("(flushing to disk)", self.f.flush)
                self._flushed = time.monotonic()
        self._frames_set = k0 + count
        self._agree_write()
        if due:
            self.frames_safe = self._frames_set

    def _test_hooks(self, frames_end: int):
        """``hooks``: a failed write from frame ``write_error_at_frame`` on, or a hold at ``hold_at_frame``."""
        if self.rank != 0:
            return
        fail, hold = hooks.get("write_error_at_frame"), hooks.get("hold_at_frame")
        if fail is not None and frames_end > fail and self._error is None:
            self._error = ("interface/intact", f"OSError: [Errno 28] No space left on device (injected by "
                                               f"{hooks.VARIABLE})")
        if hold is not None and frames_end > hold and not self._held:
            self._held = True
            hooks.hold(f"{self.path}.held")

    def interface_events(self, k0: int, fields: dict, time_of) -> int:
        """Append every rank's bond events at index k0 of /interface/events, in the contract's order: by step,
        then site, then kind.  ``fields`` holds one array per event dataset of the contract but ``time``
        (``EVENT_DATASETS``: the drive steps, global sites, kinds, partners, the bonds' stored energies, ...),
        all of one length.  Collective, also for a rank with none; ``time_of(steps)`` gives their times
        (l/c_r).  Returns the events in the file, the same on every rank.

        Sites are dealt to the ranks in increasing order, so the order is by step, then rank, then each
        rank's own (site, kind) order: each rank sorts its own events and learns where they go from
        histograms over steps (``parallel.pieces.place_by_step``); no rank holds another's events, but rank
        0 of the gathering writer, one rank's at a time."""
        names = [name for name in EVENT_DATASETS if name != "time"]
        mine = {name: np.asarray(fields[name], EVENT_DATASETS[name][0]) for name in names}
        order = np.lexsort((mine["kind"], mine["site"], mine["step"]))
        data = {name: values[order] for name, values in mine.items()}
        data["time"] = np.asarray(time_of(data["step"]), np.float64)
        where, count = place_by_step(self.comm if self.size > 1 else None, data["step"])
        total = k0 + count
        if count == 0:
            return total
        self._agree_write()            # before the collective resize below
        if self.f is not None:
            def grow():
                for name in EVENT_DATASETS:
                    self._ds(f"interface/{EVENTS}/{name}").resize((total,))
                self._ds(f"interface/{EVENTS}").attrs["events_written"] = total
            self._write(f"interface/{EVENTS}", grow)
        self._agree_write()
        where += k0
        self._write_pieces([(f"interface/{EVENTS}/{name}", where, data[name]) for name in EVENT_DATASETS])
        self._agree_write()
        return total

    def forces(self, fx, fdrive) -> dict:
        """Rank 0: the per-frame sums over the whole interface and every driven node, correctly rounded
        (``parallel.exact_sum``: each rank's share summed exactly, the shares merged exactly through a
        reduction tree, rounded once), so the same bits on any rank count, whatever the order of the
        terms; collective.  friction_force = sum of the bonds' x-forces on the block, drive_force = sum of
        the drive's x-forces, mu = -friction_force / F_N.  {} on the other ranks."""
        got = exact_sums(self.comm if self.size > 1 else None, [fx, np.asarray(fdrive, np.float64)], root=0)
        if got is None:
            return {}
        friction, drive = got
        mu = -friction / self.fn if self.fn > 0 else np.full(len(friction), np.nan)
        return {"friction_force": friction, "drive_force": drive, "mu": mu}

    def follow(self, sites: tuple):
        """The slabs followed the drift: this rank's frames start at global site ``sites[0]`` and its drive forces
        are those of the driven nodes ``sites[1]`` (``engine.simulation.Simulation.output_sites``)."""
        self.frame_site0, self.driven_gid = int(sites[0]), np.asarray(sites[1])

    def snapshot(self, k, t, pos, vel, sig, partner, far_pos):
        """Snapshot ``k`` at time ``t`` (l/c_r) of my OWNED nodes, in global id order: positions ``pos``
        (n, 3, a), velocities ``vel`` (n, 3), stresses ``sig`` (n, 3: sxx, syy, sxy); of my sites: the
        substrate column each is bonded to, ``partner`` (-1 broken), and ``far_pos`` (ns, 3) the position of
        the node at the far end of its interface cell (the partner's substrate node; its top node while
        broken or on a rigid substrate).  Collective."""
        partner = np.asarray(partner)
        other = self.bottom_gid_of_site(np.maximum(partner, 0))
        far_gid = np.where((partner >= 0) & (other >= 0), other, self.top_gid).astype(np.int64)
        fields = {"points": pos, "velocity": vel, "sxx": sig[:, 0], "syy": sig[:, 1], "sxy": sig[:, 2]}
        self._agree_write()            # no rank enters the collective writes after a failure of its own
        self._write_pieces(snapshot_pieces(self.mesh, self.share, k, fields, far_gid, far_pos,
                                           (partner >= 0).astype(np.uint8), self.bulk_cells))
        self._agree_write()            # before the collective resize and attribute below
        if self.f is not None:
            def steps():
                values = self._ds(f"{VTKHDF}/Steps/Values")
                values.resize((k + 1,))
                if self.root:
                    values[k] = t
                # NSteps must never be below len(Values): VTK's reader corrupts memory otherwise.
                self._ds(f"{VTKHDF}/Steps").attrs["NSteps"] = np.int64(k + 1)
            self._write(f"{VTKHDF}/Steps", steps)
        self._agree_write()

    def flush(self):
        """Everything written so far onto disk (collective): done at start-up and before each checkpoint."""
        if self.f is not None:
            self._write("(flushing to disk)", self.f.flush)
            self._flushed = time.monotonic()
        self._agree_write()
        self.frames_safe = self._frames_set

    def set_attrs(self, attrs: dict):
        """Root attributes (collective under mpio): e.g. the run's timings (``contract.TIMINGS``)."""
        if self.f is not None:
            def put():
                for k, v in attrs.items():
                    self.f.attrs[k] = v
            self._write("(attributes)", put)
        self._agree_write()

    def set_timings(self, timings: dict):
        self.set_attrs({TIMING_PREFIX + k: float(v) for k, v in timings.items()})

    def mark_failed(self, reason: str) -> bool:
        """From the monitor thread of rank 0 in gather mode, while the other ranks may hang: status
        "failed: REASON", flushed.  Not collective; False when this rank does not hold the file alone."""
        if self.f is None or self.mode == "mpio":
            return False
        if not self._status_on_disk(f"failed: {reason}"):
            return False
        try:
            self.f.flush()                              # the rest, as far as it goes
        except Exception:                               # noqa: BLE001 - a best effort before an abort
            pass
        return True

    def close(self, status: str = "complete"):
        """Close, then set the status (collective).  A close that fails (HDF5 writes what it still holds)
        is a WriteError on every rank, the status "failed: " and why; after an earlier failure it closes as
        best it can, quietly, and the status is ``status`` (the caller's "failed: REASON")."""
        err = None
        if self.f is not None:
            f, self.f = self.f, None
            # Close the file first: it closes every object in it, so the handles freed next write nothing.
            try:
                if self._status_at is None:         # nowhere known to write it after the close: before it
                    put_status(f, status)
                f.close()
            except (OSError, RuntimeError) as e:
                err = _hdf5_error_line(e)
                # Never close twice, and never free the objects of a file whose close failed: HDF5 (1.14)
                # crashes on either.  They are kept until the process ends (``cli.run`` ends it at once).
                _UNCLOSABLE.append((f, self._handles))
            self._handles = {}
        if getattr(self, "_prev_unraisable", None) is not None:
            if err is None:
                import gc
                gc.collect()                            # free what is left while failures are still caught
            sys.unraisablehook, self._prev_unraisable = self._prev_unraisable, None
        if err and self._error is None:
            self._error = ("(closing the file)", err)
            status = f"failed: cannot write {self.path} ({err}; closing the file)"
        self._status_on_disk(status)
        self._agree_write()

    def _status_on_disk(self, status: str) -> bool:
        """Rank 0: write ``status`` over /status's bytes in the file, directly (no HDF5) and synced: they were
        written whole when the file was made, so this needs no new space and changes nothing else, and HDF5
        holds no newer copy of them.  Done once HDF5 has closed the file, or failed to; False when it cannot
        be done (no such bytes known, or the write failed)."""
        if self._status_at is None or self.rank != 0:
            return False
        try:
            fd = os.open(self.path, os.O_WRONLY)
            try:
                os.pwrite(fd, status_value(status).tobytes(), self._status_at)
                os.fsync(fd)
            finally:
                os.close(fd)
            return True
        except OSError:
            return False


def _split(name, rows, values, cap: int):
    """A piece as pieces of at most ``cap`` bytes each (cut along its first axis), so that the gathering
    writer's messages stay small whatever a rank holds."""
    values = np.asarray(values)
    per_row = max(values.nbytes // max(len(values), 1), 1)
    step = max(cap // per_row, 1)
    if len(values) <= step:
        return [(name, rows, values)]
    if isinstance(rows, np.ndarray):
        return [(name, rows[i:i + step], values[i:i + step]) for i in range(0, len(values), step)]
    first, rest = rows[0], rows[1:]
    return [(name, (slice(first.start + i, first.start + min(i + step, len(values))),) + rest, values[i:i + step])
            for i in range(0, len(values), step)]


def _by_dataset(pieces: list):
    """[(dataset, [(rows, values), ...])]: consecutive pieces of one dataset together, rows None left out."""
    out = []
    for name, rows, values in pieces:
        if not out or out[-1][0] != name:
            out.append((name, []))
        if rows is not None:
            out[-1][1].append((rows, values))
    return out


def _h5_write(ds, parts: list, dxpl=None):
    """Write ``parts`` [(rows, values)] of dataset ``ds`` as one selection, through HDF5 directly (h5py's
    slicing skips an empty selection, which would leave a collective write short of a rank): rows a tuple
    of slices (a block of the leading axes, whole along the others) or an increasing int array (elements
    of a 1-D dataset), the parts in increasing order in the file; no parts: nothing (this rank's part of a
    collective write)."""
    space = ds.id.get_space()
    space.select_none()
    chunks = []
    points = [rows for rows, _ in parts if isinstance(rows, np.ndarray) and len(rows)]
    if points:
        space.select_elements(np.concatenate(points).astype(np.uint64).reshape(-1, 1))
    for rows, values in parts:
        if isinstance(rows, np.ndarray):
            if len(rows):
                chunks.append(np.reshape(values, (len(rows),)))
            continue
        start = tuple(r.start for r in rows) + (0,) * (len(ds.shape) - len(rows))
        count = tuple(r.stop - r.start for r in rows) + tuple(ds.shape[len(rows):])
        if all(count):
            space.select_hyperslab(start, count, op=h5s.SELECT_OR)
            chunks.append(np.reshape(values, count))
    if not chunks:
        memory = h5s.create_simple((1,))
        memory.select_none()
        data = np.zeros(1, ds.dtype)
    else:
        # The file selection runs in increasing order, and so do the parts: their values one after another.
        data = np.ascontiguousarray(chunks[0] if len(chunks) == 1 else
                                    np.concatenate([c.reshape(-1) for c in chunks]), ds.dtype)
        memory = h5s.create_simple(data.shape if len(chunks) == 1 else (data.size,))
    ds.id.write(memory, space, data, dxpl=dxpl)


def _hdf5_error_line(e: BaseException) -> str:
    """An h5py/HDF5 error as one line: HDF5's multi-line "file write failed" text becomes its errno text."""
    import re
    text = str(e)
    m = re.search(r"error message = '([^']*)'", text)
    head = text.split("(")[0].strip() if "(" in text else text.splitlines()[0] if text else ""
    if m:
        return f"{e.__class__.__name__}: {head} ({m.group(1)})"
    return f"{e.__class__.__name__}: {' '.join(text.split())}"
