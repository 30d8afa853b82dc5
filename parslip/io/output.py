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

import datetime as _dt
import os
import socket
import subprocess

import h5py
import numpy as np

from .. import __version__
from ..errors import ConfigError
from ..model.lattice import BOTTOM, TOP
from ..scene.schema import to_toml
from .contract import FRAME_FIELDS, INTERFACE_DATASETS

VTK_LINE = 3


def git_commit() -> str:
    """The commit of the parslip checkout, with '-dirty' for local changes; 'unknown' outside git."""
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    try:
        top = subprocess.run(["git", "rev-parse", "--show-toplevel"], cwd=here, capture_output=True, text=True,
                             timeout=5).stdout.strip()
        # Only parslip's own checkout counts, not a repository it happens to be installed inside.
        if not top or not os.path.samefile(os.path.join(top, "parslip"), here):
            return "unknown"
        rev = subprocess.run(["git", "rev-parse", "HEAD"], cwd=here, capture_output=True, text=True,
                             timeout=5).stdout.strip()
        if not rev:
            return "unknown"
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=here,
                               capture_output=True, text=True, timeout=5).stdout.strip()
        return rev + ("-dirty" if dirty else "")
    except (OSError, subprocess.SubprocessError, ValueError):
        return "unknown"


def hdf5_mode(size: int, comm=None) -> str:
    # With a communicator, an MPI-enabled h5py writes through mpio on any rank count, one included.
    return "mpio" if (size > 1 or comm is not None) and h5py.get_config().mpi else "gather"


class Output:
    """Writes the contract above; every method is collective over the ranks."""

    def __init__(self, path: str, sim, comm=None, provenance: dict | None = None):
        self.sim, self.comm = sim, comm
        st, lay, lat = sim.setup, sim.layout, sim.setup.lattice
        self.rank = lay.rank
        self.size = lay.size
        self.mode = hdf5_mode(self.size, comm)
        self.root = self.rank == 0
        self.f = self._open(path, comm)

        # My slices of the global arrays: OWNED nodes are a contiguous range of global ids.
        state = sim.state
        self.node0 = int(state.gid[0]) if state.n_owned else 0
        self.site0 = state.site0() if lat.has_interface else 0
        c0, c1 = lay.col_range
        nodes = lat.nodes_in_columns(c0, c1)
        nbr = lat.neighbour_gids(nodes)[:, :3]           # bonds 0..2: each bulk bond once
        has = nbr >= 0
        self.bulk_cells = np.stack([np.repeat(nodes["gid"][:, None], 3, 1)[has], nbr[has]],
                                   axis=1).astype(np.int64)
        counts = self._allgather(len(self.bulk_cells))
        self.cell0 = int(sum(counts[:self.rank]))
        self.n_bulk_cells = int(sum(counts))
        self.n_nodes, self.n_sites = lat.n_nodes, lat.n_top_sites
        self.n_cells = self.n_bulk_cells + self.n_sites
        lo, hi = lay.owned_sites() if lat.has_interface else (0, 0)
        self.top_gid = lat.gid(TOP, 0, np.arange(lo, hi)).astype(np.int64)
        # A bond to a rigid substrate has no substrate node: drawn, like a broken bond, as a point-line.
        self.bottom_gid_of_site = ((lambda q: np.full(np.shape(q), -1, np.int64)) if lat.rigid else
                                   (lambda q: lat.gid(BOTTOM, lat.bottom.rows - 1, q)))
        self._create(st, provenance or {})

    # ------------------------------------------------------------ plumbing --
    def _open(self, path, comm):
        """Open for writing; a file that cannot be opened is bad input on every rank."""
        err, f = None, None
        try:
            if self.mode == "mpio":
                f = h5py.File(path, "w", driver="mpio", comm=comm)
            elif self.root:
                f = h5py.File(path, "w")
        except OSError as e:
            err = f"--out {path!r}: cannot open for writing ({e.__class__.__name__}: {e}); " \
                  "accepted: a writable path not held open by another program"
        if self.size > 1:
            errs = [m for m in comm.allgather(err) if m]
            err = errs[0] if errs else None
        if err:
            if f is not None:
                f.close()
            raise ConfigError(err)
        return f

    def _allgather(self, x):
        return [x] if self.comm is None or self.size == 1 else self.comm.allgather(x)

    def _put(self, name, index, data):
        """Write my slice ``index`` (a tuple of slices) of dataset ``name``."""
        if self.mode == "mpio":
            self.f[name][index] = data
            return
        parts = [(index, data)] if self.size == 1 else self.comm.gather((index, data), root=0)
        if self.root:
            ds = self.f[name]
            for idx, d in parts:
                if np.size(d):
                    ds[idx] = d

    def _create(self, st, prov):
        """Create every dataset at its final size (collective under mpio)."""
        f = self.f
        if f is None:
            return
        lat = st.lattice
        nf, ns, N, M = st.n_frames, self.n_sites, self.n_nodes, self.n_cells
        S = st.n_snapshots
        a = f.attrs
        a["scene"] = to_toml(st.scene)
        for k, v in prov.items():
            a[k] = v
        a["parslip_version"] = __version__
        a.setdefault("git_commit", "unknown")
        a["status"] = "running"
        a["hdf5_mode"] = self.mode
        a["n_ranks"] = self.size
        a["n_nodes"] = N
        a["n_steps"] = st.n_steps
        a["n_drive_steps"] = st.n_drive
        a["dt"] = st.dt
        a["dt_limit"] = st.dt_limit
        a["omega_max"] = st.omega_max
        a["omega_method"] = st.omega_method
        a["c_s"], a["c_l"], a["c_r"] = st.material.c_s, st.material.c_l, st.material.c_r
        a["c_surface_born"] = st.material.c_surface_born
        a["kn_top"], a["kt_top"] = st.material.kn_top, st.material.kt_top
        a["l"] = st.l
        a["units"] = ("internal: a = 1, node mass = 1, velocity unit " + st.material.velocity_unit +
                      "; /interface: lengths in l, time in l/c_r; VTKHDF: positions in a, "
                      "velocity in internal units, stress in rho c_r^2, step times in l/c_r")
        g = f.create_group("interface")
        g.attrs["frame_every_steps"] = st.frame_every
        g.attrs["frames_written"] = 0
        for name, (dt_, per_frame, unit) in INTERFACE_DATASETS.items():
            shape = (nf, ns) if per_frame else ((nf,) if name == "time" else (ns,))
            ds = g.create_dataset(name, shape=shape, dtype=dt_,
                                  chunks=(max(1, min(nf, (1 << 16) // max(ns, 1))), ns)
                                  if len(shape) == 2 and ns else None)
            ds.attrs["units"] = unit
        if self.root:
            g["time"][...] = [st.to_lcr(k * st.frame_every * st.dt) for k in range(nf)]
            g["x"][...] = (np.arange(ns) + 0.5) / ns    # node s stands at the middle of its spacing
        if S == 0:          # no snapshots asked for: no empty VTKHDF group either
            return
        v = f.create_group("VTKHDF")
        v.attrs["Version"] = np.array([2, 2], np.int64)
        v.attrs["Type"] = np.bytes_(b"UnstructuredGrid")
        i8 = np.int64
        for name, shape, dt_ in (("NumberOfPoints", (S,), i8), ("NumberOfCells", (S,), i8),
                                 ("NumberOfConnectivityIds", (S,), i8), ("Points", (S * N, 3), np.float64),
                                 ("Types", (S * M,), np.uint8), ("Offsets", (S * (M + 1),), i8),
                                 ("Connectivity", (S * 2 * M,), i8)):
            v.create_dataset(name, shape=shape, dtype=dt_)
        pd, cd = v.create_group("PointData"), v.create_group("CellData")
        pd.create_dataset("velocity", shape=(S * N, 3), dtype=np.float64)
        for name in ("sxx", "syy", "sxy"):
            pd.create_dataset(name, shape=(S * N,), dtype=np.float64)
        for name in ("interface", "intact"):
            cd.create_dataset(name, shape=(S * M,), dtype=np.uint8)
        s = v.create_group("Steps")
        s.attrs["NSteps"] = i8(0)
        s.create_dataset("Values", shape=(0,), maxshape=(max(S, 1),), dtype=np.float64, chunks=(max(S, 1),))
        k = np.arange(S, dtype=i8)
        consts = {"PartOffsets": k, "NumberOfParts": np.ones(S, i8), "PointOffsets": k * N,
                  "CellOffsets": k * M, "ConnectivityIdOffsets": k * 2 * M}
        for name in consts:
            s.create_dataset(name, shape=(S,), dtype=i8)
        po, co = s.create_group("PointDataOffsets"), s.create_group("CellDataOffsets")
        for name in ("velocity", "sxx", "syy", "sxy"):
            po.create_dataset(name, shape=(S,), dtype=i8)
        for name in ("interface", "intact"):
            co.create_dataset(name, shape=(S,), dtype=i8)
        if self.root:
            for name, val in consts.items():
                s[name][...] = val
            for name in ("velocity", "sxx", "syy", "sxy"):
                po[name][...] = k * N
            for name in ("interface", "intact"):
                co[name][...] = k * M
            v["NumberOfPoints"][...] = N
            v["NumberOfCells"][...] = M
            v["NumberOfConnectivityIds"][...] = 2 * M
            offs = 2 * np.arange(M + 1, dtype=i8)
            for j in range(S):
                v["Offsets"][j * (M + 1):(j + 1) * (M + 1)] = offs
                v["Types"][j * M:(j + 1) * M] = VTK_LINE

    # --------------------------------------------------------------- writes --
    def interface_frames(self, k0, count, frames):
        """Frames k0 .. k0 + count - 1 from the buffer ``frames`` (``engine.loop.Frames``) of my sites."""
        ns = frames.intact.shape[1]
        sl = (slice(k0, k0 + count), slice(self.site0, self.site0 + ns))
        for name in FRAME_FIELDS:
            self._put(f"interface/{name}", sl, getattr(frames, name)[:count])
        if self.f is not None:
            self.f["interface"].attrs["frames_written"] = k0 + count

    def snapshot(self, k, t, pos, vel, sig, partner):
        N, M = self.n_nodes, self.n_cells
        p0 = k * N + self.node0
        nodes = slice(p0, p0 + len(pos))
        self._put("VTKHDF/Points", (nodes,), pos)
        self._put("VTKHDF/PointData/velocity", (nodes,), vel)
        for j, name in enumerate(("sxx", "syy", "sxy")):
            self._put(f"VTKHDF/PointData/{name}", (nodes,), sig[:, j])
        nb = len(self.bulk_cells)
        c0 = k * M + self.cell0
        self._put("VTKHDF/Connectivity", (slice(2 * c0, 2 * (c0 + nb)),), self.bulk_cells.ravel())
        self._put("VTKHDF/CellData/interface", (slice(c0, c0 + nb),), np.zeros(nb, np.uint8))
        self._put("VTKHDF/CellData/intact", (slice(c0, c0 + nb),), np.ones(nb, np.uint8))
        ns = len(partner)
        other = self.bottom_gid_of_site(np.maximum(partner, 0))
        other = np.where((partner >= 0) & (other >= 0), other, self.top_gid)
        iface = np.stack([self.top_gid, other], axis=1).astype(np.int64)   # broken: a point-line
        i0 = k * M + self.n_bulk_cells + self.site0
        self._put("VTKHDF/Connectivity", (slice(2 * i0, 2 * (i0 + ns)),), iface.ravel())
        self._put("VTKHDF/CellData/interface", (slice(i0, i0 + ns),), np.ones(ns, np.uint8))
        self._put("VTKHDF/CellData/intact", (slice(i0, i0 + ns),), (partner >= 0).astype(np.uint8))
        if self.f is not None:
            s = self.f["VTKHDF/Steps"]
            s["Values"].resize((k + 1,))
            if self.root:
                s["Values"][k] = t
            # NSteps must never be below len(Values): VTK's reader corrupts memory otherwise.
            s.attrs["NSteps"] = np.int64(k + 1)

    def close(self, status: str = "complete"):
        if self.f is not None:
            self.f.attrs["status"] = status
            self.f.close()
            self.f = None
