"""The one HDF5 file a run writes: the interface record, snapshots, provenance.

Responsible for writing the output contract of ``io.contract`` (read its
docstring for the datasets and their units).

Sites are ordered by x.  Every dataset has a fixed size known at the start,
and each rank's share of it is one contiguous slice (global ids run column
by column).  With an MPI-enabled h5py, every rank writes its own slices
through the ``mpio`` driver; otherwise rank 0 gathers the slices and writes
the same layout.  Either way the file is identical for any rank count.
"""
from __future__ import annotations

import os
import sys
import time

from dataclasses import dataclass

import h5py
import numpy as np

from .. import hooks
from ..version import __version__
from ..errors import ConfigError, WriteError
from ..model.lattice import BOTTOM, TOP
from .contract import (ENERGY, ENERGY_DATASETS, EVENT_DATASETS, EVENTS, FRAME_FIELDS, INTERFACE_DATASETS,
                       PER_FRAME_1D, SITE_DATASETS, STATUS, TIMING_PREFIX, put_status, status_value)
from .scenefile import to_toml

VTK_LINE = 3
# Chunks.  A write that covers whole chunks goes straight to the file; one that covers part of a chunk
# goes through HDF5's chunk cache (1 MiB per dataset), or, for a chunk larger than the cache, reads the chunk
# back first.  So: an interface dataset's chunk holds one frame buffer's worth of frames (the blocks the
# loop hands over, aligned to it), and a snapshot dataset's chunk one snapshot's rows, at most CHUNK_BYTES
# (measured on 100 sites: 1.7 against 2.9 us per frame with 655-frame chunks; a 1,000-node snapshot's
# Points written into 65,536-row chunks read 1.5 MB back each time).
CHUNK_BYTES = 1 << 20
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

        # My slices of the global arrays: OWNED nodes are a contiguous range of global ids.
        self.node0, self.site0 = spec.node0, spec.site0
        c0, c1 = spec.col_range
        self.bulk_cells = _bulk_cells(lat, c0, c1)
        # The bulk cells' constant fields (not interface, intact), written with each snapshot.
        self._bulk_zeros = np.zeros(len(self.bulk_cells), np.uint8)
        self._bulk_ones = np.ones(len(self.bulk_cells), np.uint8)
        counts = self._allgather(len(self.bulk_cells))
        self.cell0 = int(sum(counts[:self.rank]))
        self.n_bulk_cells = int(sum(counts))
        self.n_nodes, self.n_sites = lat.n_nodes, lat.n_top_sites
        self.n_cells = self.n_bulk_cells + self.n_sites
        lo, hi = spec.owned_sites
        self.top_gid = lat.gid(TOP, 0, np.arange(lo, hi)).astype(np.int64)
        self.driven_gid = spec.driven_gid
        self.fn = float(st.scene["load.FN"])
        # A bond to a rigid substrate has no substrate node: drawn, like a broken bond, as a point-line.
        self.bottom_gid_of_site = ((lambda q: np.full(np.shape(q), -1, np.int64)) if lat.rigid else
                                   (lambda q: lat.gid(BOTTOM, lat.bottom.rows - 1, q)))
        self._catch_unraisable()
        self._old_snapshots = 0            # snapshot slots the file held before a restart grew it
        if resume:
            self._resume(st, resume)
        else:
            self._write("(creating the datasets)", lambda: self._create(st, provenance or {}))
        if self.spec.snapshots_total and st.scene["output.fields"] != "interface":
            old = self._old_snapshots if self.size == 1 or self.mode == "mpio" else \
                self.comm.bcast(self._old_snapshots, root=0)
            self._cell_constants(old, self.spec.snapshots_total)
        try:
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

    def _allgather(self, x):
        return [x] if self.comm is None or self.size == 1 else self.comm.allgather(x)

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

    def _put(self, name, index, data):
        """Write my slice ``index`` (a tuple of slices) of dataset ``name``."""
        if self.mode == "mpio":
            self._write(name, lambda: self._ds(name).__setitem__(index, data))
            return
        parts = [(index, data)] if self.size == 1 else self.comm.gather((index, data), root=0)
        if self.root:
            def put():
                ds = self._ds(name)
                for idx, d in parts:
                    if np.size(d):
                        ds[idx] = d
            self._write(name, put)

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
        v = self._handles["VTKHDF"] = f.create_group("VTKHDF")
        v.attrs["Version"] = np.array([2, 2], np.int64)
        v.attrs["Type"] = np.bytes_(b"UnstructuredGrid")
        S = self.spec.snapshots_total
        for name, shape in self._vtk_shapes(S).items():
            dt_ = np.uint8 if name in ("Types", "CellData/interface", "CellData/intact") else (
                np.float64 if name.startswith(("Points", "PointData")) or name == "Steps/Values" else np.int64)
            if name == "Steps/Values":
                shape = (0,)              # grows with each snapshot: VTK's reader needs len(Values) == NSteps
            self._handles[f"VTKHDF/{name}"] = v.create_dataset(
                name, shape=shape, maxshape=(None,) + shape[1:], dtype=dt_,
                chunks=(self._chunk_rows(name, shape),) + shape[1:], dcpl=_early())
        self._ds("VTKHDF/Steps").attrs["NSteps"] = np.int64(0)
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
        """Per-step constants of snapshots k0..k1-1 (one part, N points, M line cells, offsets into the flat
        arrays), written at once when the file is made or grows: a snapshot then writes its data only."""
        if not self.root or k1 <= k0:
            return
        N, M = self.n_nodes, self.n_cells
        k = np.arange(k0, k1, dtype=np.int64)
        for name, val in (("NumberOfPoints", np.full(len(k), N)), ("NumberOfCells", np.full(len(k), M)),
                          ("NumberOfConnectivityIds", np.full(len(k), 2 * M)), ("Steps/PartOffsets", k),
                          ("Steps/NumberOfParts", np.ones(len(k), np.int64)), ("Steps/PointOffsets", k * N),
                          ("Steps/CellOffsets", k * M), ("Steps/ConnectivityIdOffsets", k * 2 * M)):
            self._ds(f"VTKHDF/{name}")[k0:k1] = val
        for name in ("velocity", "sxx", "syy", "sxy"):
            self._ds(f"VTKHDF/Steps/PointDataOffsets/{name}")[k0:k1] = k * N
        for name in ("interface", "intact"):
            self._ds(f"VTKHDF/Steps/CellDataOffsets/{name}")[k0:k1] = k * M
        # Every step's cells are lines: offsets into its connectivity, and their type (one step at a time,
        # so no array of all the steps' cells is ever held).
        offsets, types = 2 * np.arange(M + 1, dtype=np.int64), np.full(M, VTK_LINE, np.uint8)
        for j in range(k0, k1):
            self._ds("VTKHDF/Offsets")[j * (M + 1):(j + 1) * (M + 1)] = offsets
            self._ds("VTKHDF/Types")[j * M:(j + 1) * M] = types

    def _cell_constants(self, k0: int, k1: int):
        """The cells of snapshots k0..k1-1 that never change, written when the file is made or grows
        (collective): each rank's bulk bonds (connectivity, interface 0, intact 1) and its interface cells'
        flag (interface 1).  A snapshot then writes only its fields and the interface bonds' state."""
        M = self.n_cells
        nb, ns = len(self.bulk_cells), len(self.top_gid)
        ones = np.ones(ns, np.uint8)
        for k in range(k0, k1):
            c0 = k * M + self.cell0
            self._put("VTKHDF/Connectivity", (slice(2 * c0, 2 * (c0 + nb)),), self.bulk_cells.ravel())
            self._put("VTKHDF/CellData/interface", (slice(c0, c0 + nb),), self._bulk_zeros)
            self._put("VTKHDF/CellData/intact", (slice(c0, c0 + nb),), self._bulk_ones)
            i0 = k * M + self.n_bulk_cells + self.site0
            self._put("VTKHDF/CellData/interface", (slice(i0, i0 + ns),), ones)

    def _chunk_rows(self, name: str, shape: tuple) -> int:
        """Rows of a VTKHDF dataset's chunk: one snapshot's rows (N points, M cells, M + 1 offsets, 2 M
        connectivity ids, 1 per-step value), at most CHUNK_BYTES, at most the dataset."""
        N, M = self.n_nodes, self.n_cells
        per = (N if name.startswith(("Points", "PointData")) else 2 * M if name == "Connectivity" else
               M + 1 if name == "Offsets" else M if name in ("Types",) or name.startswith("CellData") else 64)
        width = int(np.prod(shape[1:])) * 8
        return int(max(1, min(per, max(1, CHUNK_BYTES // width), max(shape[0], 1))))

    def _vtk_shapes(self, S: int) -> dict:
        """Shapes of the VTKHDF datasets for S snapshots (N points, M line cells each)."""
        N, M = self.n_nodes, self.n_cells
        shapes = {"NumberOfPoints": (S,), "NumberOfCells": (S,), "NumberOfConnectivityIds": (S,),
                  "Points": (S * N, 3), "Types": (S * M,), "Offsets": (S * (M + 1),), "Connectivity": (S * 2 * M,),
                  "PointData/velocity": (S * N, 3), "CellData/interface": (S * M,), "CellData/intact": (S * M,),
                  "Steps/Values": (S,), "Steps/PartOffsets": (S,), "Steps/NumberOfParts": (S,),
                  "Steps/PointOffsets": (S,), "Steps/CellOffsets": (S,), "Steps/ConnectivityIdOffsets": (S,)}
        for name in ("sxx", "syy", "sxy"):
            shapes[f"PointData/{name}"] = (S * N,)
        for name in ("velocity", "sxx", "syy", "sxy"):
            shapes[f"Steps/PointDataOffsets/{name}"] = (S,)
        for name in ("interface", "intact"):
            shapes[f"Steps/CellDataOffsets/{name}"] = (S,)
        return shapes

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
            if "VTKHDF" in f:
                old = self._old_snapshots = f["VTKHDF/NumberOfPoints"].shape[0]
                for name, shape in self._vtk_shapes(self.spec.snapshots_total).items():
                    if name != "Steps/Values":
                        f["VTKHDF"][name].resize(shape[0], axis=0)
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
        sl = (slice(k0, k0 + count), slice(self.site0, self.site0 + ns))
        self._test_hooks(k0 + count)
        for name in FRAME_FIELDS:
            self._put(f"interface/{name}", sl, getattr(frames, name)[:count])
        sums = self.forces(frames.fx[:count], frames.fdrive[:count])
        if self.root:
            st = self.spec.setup
            steps = frames.step[:count] - st.n_drive_start
            moved = steps if held is None else np.minimum(steps, held)
            loader = moved * st.dt * st.v0 / st.l if st.drive.on else np.zeros(count)

            def put():
                self._ds("interface/time")[k0:k0 + count] = times
                self._ds("interface/step")[k0:k0 + count] = steps
                self._ds("interface/loader")[k0:k0 + count] = loader
                for name, values in sums.items():
                    self._ds(f"interface/{name}")[k0:k0 + count] = values
                if energy is not None and ENERGY in self.f:
                    for name, values in energy.items():
                        self._ds(f"{ENERGY}/{name}")[k0:k0 + count] = values
            self._write("interface/time", put)
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
        (l/c_r).  Returns the events in the file, the same on every rank."""
        names = [name for name in EVENT_DATASETS if name != "time"]
        mine = tuple(np.asarray(fields[name], EVENT_DATASETS[name][0]) for name in names)
        parts = [mine] if self.size == 1 else self.comm.gather(mine, root=0)
        total = None
        if self.root:
            cols = dict(zip(names, (np.concatenate(col) for col in zip(*parts))))
            order = np.lexsort((cols["kind"], cols["site"], cols["step"]))
            data = {name: col[order] for name, col in cols.items()}
            data["time"] = np.asarray(time_of(data["step"]), np.float64)
            total = k0 + len(order)
        if self.size > 1:
            total = self.comm.bcast(total, root=0)
        if total == k0:
            return total
        self._agree_write()            # before the collective resize below
        if self.f is not None:
            def grow():
                g = self._ds(f"interface/{EVENTS}")
                for name in EVENT_DATASETS:
                    self._ds(f"interface/{EVENTS}/{name}").resize((total,))
                if self.root:
                    for name in EVENT_DATASETS:
                        self._ds(f"interface/{EVENTS}/{name}")[k0:total] = data[name]
                g.attrs["events_written"] = total
            self._write(f"interface/{EVENTS}", grow)
        self._agree_write()
        return total

    def forces(self, fx, fdrive) -> dict:
        """Rank 0: the per-frame sums over the whole interface and every driven node, in global order, so
        they are the same bits on any rank count (each rank's values travel to rank 0, which sums them):
        friction_force = sum of the bonds' x-forces on the block, drive_force = sum of the drive's
        x-forces, mu = -friction_force / F_N."""
        if self.size > 1:
            parts = self.comm.gather((self.site0, fx, self.driven_gid, fdrive), root=0)
        else:
            parts = [(self.site0, fx, self.driven_gid, fdrive)]
        if not self.root:
            return {}
        count = fx.shape[0]
        if len(parts) == 1:                      # one rank: its arrays are already whole and in order
            fx_all, fd_all = fx, np.asarray(fdrive, np.float64)
        else:
            fx_all = np.zeros((count, self.n_sites))
            gids, fd = [], []
            for s0, f, g, d in parts:
                fx_all[:, s0:s0 + f.shape[1]] = f
                gids.append(g)
                fd.append(d)
            gids = np.concatenate(gids) if gids else np.zeros(0, np.int64)
            fd_all = np.concatenate(fd, axis=1) if fd else np.zeros((count, 0))
            fd_all = np.ascontiguousarray(fd_all[:, np.argsort(gids, kind="stable")], dtype=np.float64)
        friction, drive = _ordered_sum(fx_all), _ordered_sum(fd_all)
        mu = -friction / self.fn if self.fn > 0 else np.full(count, np.nan)
        return {"friction_force": friction, "drive_force": drive, "mu": mu}

    def snapshot(self, k, t, pos, vel, sig, partner):
        N, M = self.n_nodes, self.n_cells
        p0 = k * N + self.node0
        nodes = slice(p0, p0 + len(pos))
        self._put("VTKHDF/Points", (nodes,), pos)
        self._put("VTKHDF/PointData/velocity", (nodes,), vel)
        for j, name in enumerate(("sxx", "syy", "sxy")):
            self._put(f"VTKHDF/PointData/{name}", (nodes,), sig[:, j])
        # The bulk cells and the cell flags that never change were written with the file (``_cell_constants``).
        ns = len(partner)
        other = self.bottom_gid_of_site(np.maximum(partner, 0))
        other = np.where((partner >= 0) & (other >= 0), other, self.top_gid)
        iface = np.stack([self.top_gid, other], axis=1).astype(np.int64)   # broken: a point-line
        i0 = k * M + self.n_bulk_cells + self.site0
        self._put("VTKHDF/Connectivity", (slice(2 * i0, 2 * (i0 + ns)),), iface.ravel())
        self._put("VTKHDF/CellData/intact", (slice(i0, i0 + ns),), (partner >= 0).astype(np.uint8))
        self._agree_write()            # before the collective resize and attribute below
        if self.f is not None:
            def steps():
                values = self._ds("VTKHDF/Steps/Values")
                values.resize((k + 1,))
                if self.root:
                    values[k] = t
                # NSteps must never be below len(Values): VTK's reader corrupts memory otherwise.
                self._ds("VTKHDF/Steps").attrs["NSteps"] = np.int64(k + 1)
            self._write("VTKHDF/Steps", steps)
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


def _hdf5_error_line(e: BaseException) -> str:
    """An h5py/HDF5 error as one line: HDF5's multi-line "file write failed" text becomes its errno text."""
    import re
    text = str(e)
    m = re.search(r"error message = '([^']*)'", text)
    head = text.split("(")[0].strip() if "(" in text else text.splitlines()[0] if text else ""
    if m:
        return f"{e.__class__.__name__}: {head} ({m.group(1)})"
    return f"{e.__class__.__name__}: {' '.join(text.split())}"


def _ordered_sum(values: np.ndarray) -> np.ndarray:
    """Each row's sum in index order, one addition at a time, ((v0 + v1) + v2) + ...: the documented order,
    not NumPy's pairwise sum; vectorised over the rows (frames), site by site."""
    if values.shape[1] == 0:
        return np.zeros(values.shape[0])
    total = values[:, 0].copy()
    for j in range(1, values.shape[1]):
        total += values[:, j]
    return total
