"""Checkpoints: everything a run needs to continue exactly, written and read by slabs, replaced atomically.

Every rank writes and reads only its own slab: its OWNED nodes, a contiguous range of global node ids
(columns [c0, c1) of the lattice, numbered column by column), and its OWNED interface sites, a contiguous
range of sites.  HALO copies are not stored: a restore refills them with the halo exchange.  So no rank
ever holds more of a checkpoint than its slab, and a checkpoint written on N ranks restarts on any M.

Format 4 ("parslip checkpoint 4").  ``OUT.ckpt.h5``, the name a user passes to ``--restart``, holds the
root attributes and one of two layouts (root attribute ``layout``):

  single   the datasets themselves, by global id, as in format 3:
             /u, /u_prev     float [nodes, 2]  displacements u(n) and u(n-1), in a (the state's float type)
             /drive0         float [nodes]     x displacement of each node when the drive started
             /drive_force    float [nodes]     the x-force the drive applied to each driven node last step
             /partner, /x0, ...  [sites]       one dataset per row the bond table saves
                                               (``model.interface.BOND_TABLE``), in the dtype it gives
           Written where h5py has MPI, collectively: every rank its contiguous block of each dataset
           (``with dset.collective``), through the ``mpio`` driver; or by the one process of a 1-rank run.
  parts    an index: /parts int64 [P, 4], row k = the node range [first, end) and the site range
           [first, end) of part k, stored as ``PARTS_DIR/k.h5`` (``parts_dir``, relative to the index's
           folder) with the same datasets for those rows alone.  Written where h5py has no MPI (PyPI's
           wheel, the default install): each rank writes its own part, with no message, and rank 0 writes
           the index (its P rows come from the slab bounds every rank holds).  One shared file cannot be
           written by several processes without MPI-IO; part files need nothing but a filesystem.

  root attributes  ``layout``, ``rows`` (the datasets each slab holds), ``n_nodes``, ``n_sites``, the step
                   n, the resolved scene (TOML), omega_max and dt, the output cursor (frames and
                   snapshots written, bond events written), the bond event counters, the energy budget's
                   totals, the run id shared with the output file, the rank count that wrote it, and
                   ``complete`` = 1, set last.

Either layout is plain HDF5, so either installation reads either: a rank opens the index, then only the
file(s) that hold its rows (the single file, or the parts that overlap its slab), and reads only those
rows, each straight into its slab's array.

Writing is atomic.  A single file is written as ``OUT.ckpt.h5.tmp``; parts go to a folder of their own
generation, ``OUT.ckpt.h5.parts/TOKEN/``, and the index to ``OUT.ckpt.h5.tmp`` once every rank's part is
on disk (fsynced, the ranks agreed).  Rank 0 then fsyncs the file and renames it over ``OUT.ckpt.h5``: a
process killed at any moment, on any rank, leaves the previous checkpoint whole.  Only then is the
previous generation's parts removed (each rank a share), and any generation a killed write left behind.

Reading: ``validate`` (rank 0, before the run) refuses with one line naming what is wrong (exit 2) a
file that is not a complete parslip checkpoint, one of another lattice, or one of another scene, except
for the keys ``SAFE_KEYS`` that may change on a restart.  A key the checkpoint's scene lacks (added
since) counts as its ``IMPLIED`` value.  Format 3 ("parslip checkpoint 3", one file by global id, written
by rank 0 alone) is read as a single layout.  A bond row an older file lacks starts at the row's
``initial`` value in the bond table (a row added since, such as a damage state, starts as a fresh run's).
"""
from __future__ import annotations

import os
import shutil
import uuid
from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError, WriteError
from ..model.interface import BOND_TABLE, BONDS
from ..parallel.collective import decide

FORMAT = "parslip checkpoint 4"          # 2: with drive_force; 3: with events_written; 4: by slabs
OLD_FORMATS = ("parslip checkpoint 3",)  # read as a single layout
SAFE_KEYS = ("drive.duration", "output.interface_dt", "output.snapshots", "output.progress_s",
             "output.buffer_frames", "output.buffer_events", "checkpoint.every", "checkpoint.wall",
             "interface.slip_reach", "interface.halo_skin", "run.watchdog", "run.overlap", "run.exchange")
# Keys added to the scene since checkpoints of this format were first written, with the value that gives
# the behaviour of the code that wrote them: a checkpoint whose scene lacks such a key was written with it.
IMPLIED = {"interface.contact": 0.0, "time.damping": "absolute", "output.energy": "balance",
           "interface.softening": 0.0, "interface.contact_friction": 0.0, "interface.nucleation.kind": "none",
           "interface.nucleation.x": [], "interface.nucleation.duration": 0.0, "interface.nucleation.speed": 0.0,
           "interface.nucleation.start": 0.0, "drive.prestress.tau0": 0.0, "drive.prestress.settle": 2.0,
           "drive.prestress.x": [0.0, 1.0]}
# Datasets by global node id, with their columns (0: one value per node), then one per bond row by site.
NODE_DATASETS = {"u": 2, "u_prev": 2, "drive0": 0, "drive_force": 0}
DATASETS = tuple(NODE_DATASETS) + BONDS.checkpoint
SINGLE, PARTS = "single", "parts"


@dataclass
class Slab:
    """One rank's share of a checkpoint: global node ids [nodes[0], nodes[1]), interface sites
    [sites[0], sites[1]), and ``arrays`` by dataset name, each holding those rows in global order."""
    nodes: tuple
    sites: tuple
    arrays: dict

    def rows(self, name: str) -> tuple[int, int]:
        """The global range of dataset ``name``'s rows."""
        return self.nodes if name in NODE_DATASETS else self.sites


def path_for(out: str) -> str:
    """The checkpoint that belongs to output file ``out``: OUT.ckpt.h5."""
    return out + ".ckpt.h5"


def parts_root(path: str) -> str:
    """The folder that holds the part files of checkpoint ``path``'s generations."""
    return path + ".parts"


def slab_table(lattice, bounds) -> np.ndarray:
    """[ranks, 4] int64: each rank's node range [first, end) and site range [first, end), from the slab
    bounds (columns) alone; global node ids run column by column, interface sites over the block's."""
    b = np.asarray(bounds, np.int64)
    out = np.zeros((len(b) - 1, 4), np.int64)
    out[:, 0], out[:, 1] = lattice.col_start[b[:-1]], lattice.col_start[b[1:]]
    if lattice.has_interface:
        lo, n = lattice.top.col0, lattice.top.cols
        out[:, 2], out[:, 3] = np.clip(b[:-1] - lo, 0, n), np.clip(b[1:] - lo, 0, n)
    return out


def initial_rows() -> dict:
    """{bond row: the value a site starts with} for the rows a checkpoint may lack (``BondRow.initial``)."""
    return {r.name: r.initial for r in BOND_TABLE if r.checkpoint is not False and r.initial is not None}


def empty_slab(nodes, sites, dtype) -> Slab:
    """A slab of zeros for these ranges, each dataset (``DATASETS``) in its checkpoint dtype."""
    arrays = {}
    for name in DATASETS:
        if name in NODE_DATASETS:
            cols = NODE_DATASETS[name]
            arrays[name] = np.zeros((nodes[1] - nodes[0],) + ((cols,) if cols else ()), dtype)
        else:
            arrays[name] = np.zeros(sites[1] - sites[0], BONDS.dtypes[name] or dtype)
    return Slab(tuple(nodes), tuple(sites), arrays)


# ------------------------------------------------------------------------------------------- writing --
_written = 0            # checkpoints this process has begun to write (the kill hook counts them)
_rank = 0               # this process's rank in the last write


def _kill_point() -> bool:
    """True where the hook ``kill_in_checkpoint`` = [RANK:]K asks this process to die halfway through
    writing its K-th checkpoint (``parslip.hooks``; RANK 0 when not given)."""
    from .. import hooks
    v = hooks.get("kill_in_checkpoint")
    return v is not None and v == (_rank, _written)


def _die(f=None):
    import signal
    if f is not None:
        f.flush()
    os.kill(os.getpid(), signal.SIGKILL)


def _fsync(path: str) -> None:
    """Flush a file, or a folder's entries, to the disk."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    except OSError:
        if not os.path.isdir(path):       # some filesystems cannot sync a folder: the files are synced
            raise
    finally:
        os.close(fd)


def write(comm, path: str, slab: Slab, attrs: dict, table: np.ndarray, collective: bool = False) -> None:
    """Write a checkpoint atomically; collective over ``comm`` (None: one rank).

    ``slab`` is this rank's share (``Simulation.checkpoint_slab``), ``table`` every rank's ranges
    (``slab_table``), ``attrs`` the scalars (the same on every rank; rank 0's are written).
    ``collective``: h5py has MPI and the output is written through mpio: one file, collectively;
    otherwise one part file per rank and an index.  Raises ``WriteError`` on every rank if any failed.
    The hook ``kill_in_checkpoint=[RANK:]K`` kills that rank with SIGKILL halfway through its K-th write.
    """
    global _written, _rank
    _written += 1
    rank, size = (comm.Get_rank(), comm.Get_size()) if comm is not None else (0, 1)
    _rank = rank
    layout = SINGLE if size == 1 or collective else PARTS
    gen = decide(comm, lambda: _new_generation(path, layout))
    err = gen.get("error")
    if err is None:
        try:
            if layout == PARTS:
                _write_part(os.path.join(parts_root(path), gen["token"], f"{rank}.h5"), slab)
            elif size == 1:
                _write_single_alone(path + ".tmp", slab)
            else:
                _write_single_collective(comm, path + ".tmp", slab, table)
        except (OSError, RuntimeError) as e:          # h5py: RuntimeError when HDF5 cannot flush metadata
            err = f"cannot write the checkpoint {path} ({e.__class__.__name__}: {e})"
        err = _first_error(comm, err)
    if err is None and rank == 0:
        try:
            _publish(path, layout, gen["token"], attrs, table)
        except (OSError, RuntimeError) as e:          # h5py: RuntimeError when HDF5 cannot flush metadata
            err = f"cannot write the checkpoint {path} ({e.__class__.__name__}: {e})"
    if comm is not None and size > 1:
        err = comm.bcast(err, root=0)          # every rank fails alike, none waits for another
    if err:
        raise WriteError(err, path=path)
    _remove_previous(comm, path, gen, rank, size)


def _first_error(comm, err):
    """The error of the lowest rank that has one, on every rank (two collectives, no gather)."""
    if comm is None or comm.Get_size() == 1:
        return err
    from mpi4py import MPI
    size = comm.Get_size()
    first = comm.allreduce(comm.Get_rank() if err else size, op=MPI.MIN)
    return None if first == size else comm.bcast(err, root=first)


def _new_generation(path: str, layout: str) -> dict:
    """Rank 0, before a write: a fresh token (and, for parts, its folder), and where the previous
    checkpoint's parts are, to remove once the new one is in place."""
    gen = {"token": uuid.uuid4().hex[:16], "old": None, "n_old": 0}
    try:
        with _h5().File(path, "r") as f:
            if f.attrs.get("layout") == PARTS:
                gen["old"] = _parts_dir(path, f.attrs)
                gen["n_old"] = int(f["parts"].shape[0])
    except (OSError, KeyError, ValueError, RuntimeError):
        pass                                   # none, or unreadable: the sweep after the write finds its parts
    if layout == PARTS:
        try:
            os.makedirs(os.path.join(parts_root(path), gen["token"]))
        except OSError as e:
            gen["error"] = f"cannot write the checkpoint {path} ({e.__class__.__name__}: {e})"
    return gen


def _h5():
    import h5py
    return h5py


def _write_rows(f, slab: Slab) -> None:
    """Every dataset of ``slab`` into the open file ``f``, as it stands (the kill hook strikes after the
    first)."""
    for name in DATASETS:
        f.create_dataset(name, data=slab.arrays[name])
        if _kill_point():
            _die(f)


def _write_part(part: str, slab: Slab) -> None:
    """This rank's part file: its rows of every dataset, fsynced."""
    with _h5().File(part, "w") as f:
        _write_rows(f, slab)
        f.attrs["format"] = FORMAT
        f.attrs["nodes"], f.attrs["sites"] = np.asarray(slab.nodes, np.int64), np.asarray(slab.sites, np.int64)
        f.attrs["complete"] = 1
    _fsync(part)


def _write_single_alone(tmp: str, slab: Slab) -> None:
    """One rank: the whole single layout (its slab is the lattice)."""
    with _h5().File(tmp, "w") as f:
        _write_rows(f, slab)


def _write_single_collective(comm, tmp: str, slab: Slab, table: np.ndarray) -> None:
    """Every rank: its contiguous block of each dataset of one file, in collective MPI-IO writes."""
    h5py = _h5()
    total = {"nodes": int(table[-1, 1]), "sites": int(table[-1, 3])}
    with h5py.File(tmp, "w", driver="mpio", comm=comm) as f:
        for name in DATASETS:
            rows = slab.arrays[name]
            n = total["nodes" if name in NODE_DATASETS else "sites"]
            ds = f.create_dataset(name, shape=(n,) + rows.shape[1:], dtype=rows.dtype)   # collective
            first = slab.rows(name)[0]
            with ds.collective:
                _put_collective(ds, first, rows)
            if _kill_point():
                _die()


def _put_collective(ds, first: int, rows: np.ndarray) -> None:
    """Rows ``first`` onwards of ``ds`` from ``rows``; a rank with none still joins the collective write
    with an empty selection (h5py 3.16's ``write_direct`` of zero rows left the other ranks waiting)."""
    from h5py import h5s
    fspace = ds.id.get_space()
    if len(rows):
        fspace.select_hyperslab((first,) + (0,) * (rows.ndim - 1), rows.shape)
        mspace = h5s.create_simple(rows.shape)
        buf = np.ascontiguousarray(rows)
    else:
        fspace.select_none()
        mspace = h5s.create_simple((1,) + rows.shape[1:])
        mspace.select_none()
        buf = np.zeros((1,) + rows.shape[1:], rows.dtype)
    ds.id.write(mspace, fspace, buf, dxpl=ds._dxpl)


def _publish(path: str, layout: str, token: str, attrs: dict, table: np.ndarray) -> None:
    """Rank 0, every slab on disk: the scalars and (parts) the index into ``PATH.tmp``, then the atomic
    rename over ``PATH``."""
    tmp = path + ".tmp"
    if layout == PARTS:
        gen_dir = os.path.join(parts_root(path), token)
        _fsync(gen_dir)                        # the parts' names are on disk before the index names them
        _fsync(parts_root(path))
    with _h5().File(tmp, "w" if layout == PARTS else "r+") as f:
        if layout == PARTS:
            f.create_dataset("parts", data=np.asarray(table, np.int64))
            f.attrs["parts_dir"] = os.path.join(os.path.basename(parts_root(path)), token)
        for k, v in attrs.items():
            f.attrs[k] = v
        f.attrs["layout"] = layout
        f.attrs["rows"] = list(DATASETS)
        f.attrs["n_nodes"], f.attrs["n_sites"] = int(table[-1, 1]), int(table[-1, 3])
        f.attrs["format"] = FORMAT
        f.flush()
        f.attrs["complete"] = 1
    _fsync(tmp)
    os.replace(tmp, path)
    _fsync(os.path.dirname(os.path.abspath(path)))   # the rename itself survives a crash


def _remove_previous(comm, path: str, gen: dict, rank: int, size: int) -> None:
    """The new checkpoint is in place: remove the previous generation's parts (rank r the parts
    r, r + size, ...), then rank 0 its folder and whatever generation a killed write left behind."""
    if gen["old"] is not None:
        for k in range(rank, gen["n_old"], size):
            try:
                os.remove(os.path.join(gen["old"], f"{k}.h5"))
            except OSError:
                pass
    if comm is not None and size > 1:
        comm.Barrier()
    if rank == 0:
        sweep(path, keep=gen["token"])


def sweep(path: str, keep: str | None = None) -> None:
    """Remove every generation of parts under ``OUT.ckpt.h5.parts`` but ``keep`` (and the folder when
    nothing is left)."""
    root = parts_root(path)
    try:
        names = os.listdir(root)
    except OSError:
        return
    for name in names:
        if name != keep:
            shutil.rmtree(os.path.join(root, name), ignore_errors=True)
    if keep is None or keep not in names:
        try:
            os.rmdir(root)
        except OSError:
            pass


def remove(path: str) -> None:
    """Remove checkpoint ``path`` and its parts (a finished sweep point's, say)."""
    try:
        os.remove(path)
    except FileNotFoundError:
        pass
    sweep(path)


# ------------------------------------------------------------------------------------------- reading --
def _parts_dir(path: str, attrs) -> str:
    return os.path.join(os.path.dirname(os.path.abspath(path)), str(attrs["parts_dir"]))


def _rows_held(f, attrs) -> tuple:
    """The datasets each slab of this checkpoint holds."""
    if "rows" in attrs:
        return tuple(str(r) for r in attrs["rows"])
    return tuple(name for name in DATASETS if name in f)           # format 3: the file's own datasets


def read(path: str, nodes, sites, dtype=None) -> tuple[Slab, dict]:
    """(this rank's slab, the attributes) of a checkpoint ``validate`` accepted: only the rows of global
    nodes [nodes[0], nodes[1]) and sites [sites[0], sites[1]), read from the file(s) holding them into
    arrays of the slab's size (the float type: ``dtype``, default the checkpoint's precision).

    Raises ConfigError (one line) when a part it needs is missing or unreadable."""
    h5py = _h5()
    try:
        with h5py.File(path, "r") as f:
            attrs = dict(f.attrs)
            held = _rows_held(f, attrs)
            slab = empty_slab(nodes, sites, np.dtype(dtype or str(attrs.get("precision", "float64"))))
            if attrs.get("layout", SINGLE) == SINGLE:
                _read_rows(f, slab, held, (0, 0, 0, 0))
                table = None
            else:
                table = f["parts"][...]
    except OSError as e:
        raise ConfigError(f"--restart {path!r}: not readable ({e.__class__.__name__}: {e}); accepted: a "
                          f"checkpoint written by parslip run") from None
    if table is not None:
        _read_parts(path, attrs, table, slab, held)
    for name, value in initial_rows().items():
        if name not in held:
            slab.arrays[name][:] = value
    return slab, attrs


def _read_parts(path: str, attrs: dict, table: np.ndarray, slab: Slab, held: tuple) -> None:
    """Read the slab's rows from each part that overlaps it."""
    h5py = _h5()
    folder = _parts_dir(path, attrs)
    for k, row in enumerate(table):
        if not (_overlap(slab.nodes, row[0:2]) or _overlap(slab.sites, row[2:4])):
            continue
        part = os.path.join(folder, f"{k}.h5")
        try:
            with h5py.File(part, "r") as f:
                if int(f.attrs.get("complete", 0)) != 1:
                    raise OSError("incomplete part")
                _read_rows(f, slab, held, row)
        except OSError as e:
            raise ConfigError(f"--restart {path!r}: its part {part} is missing or unreadable "
                              f"({e.__class__.__name__}: {e}); accepted: a checkpoint with every part "
                              f"in {folder}") from None


def _overlap(a, b) -> bool:
    return max(a[0], b[0]) < min(a[1], b[1])


def _read_rows(f, slab: Slab, held: tuple, row) -> None:
    """Copy into ``slab`` the rows it needs of file ``f``, whose datasets start at global node row[0] and
    site row[2]."""
    for name in held:
        if name not in slab.arrays:
            continue
        want = slab.rows(name)
        first = int(row[0] if name in NODE_DATASETS else row[2])
        ds = f[name]
        lo, hi = max(want[0], first), min(want[1], first + ds.shape[0])
        if lo < hi:
            out = slab.arrays[name]
            ds.read_direct(out, np.s_[lo - first:hi - first], np.s_[lo - want[0]:hi - want[0]])


def validate(path: str, scene: dict, n_nodes: int, n_sites: int) -> dict:
    """Check a checkpoint before use (rank 0); returns its attributes.  Raises ConfigError (exit 2) with
    one line."""
    from .scenefile import loads
    attrs, shapes, held = _index(path)
    fmt = attrs.get("format")
    if fmt != FORMAT and fmt not in OLD_FORMATS:
        old = str(fmt or "").startswith("parslip checkpoint")
        raise ConfigError(f"--restart {path!r}: " + (f"a checkpoint of an older format ({fmt!r}); accepted: "
                                                     f"{', '.join((FORMAT,) + OLD_FORMATS)}"
                                                     if old else "not a parslip checkpoint; accepted: a file written "
                                                     "by parslip run as OUT.ckpt.h5"))
    if int(attrs.get("complete", 0)) != 1:
        raise ConfigError(f"--restart {path!r}: incomplete checkpoint (the writer stopped before finishing); "
                          f"accepted: a complete checkpoint")
    _check_shapes(path, attrs, shapes, held, n_nodes, n_sites)
    saved = loads(str(attrs["scene"]))
    for key in sorted(set(saved) | set(scene)):
        if key in SAFE_KEYS:
            continue
        if saved.get(key, IMPLIED.get(key)) != scene.get(key):
            raise ConfigError(f"--restart {path!r}: {key} = {scene.get(key)!r} but the checkpoint was written with "
                              f"{saved.get(key, IMPLIED.get(key))!r}; accepted: the same scene, except "
                              f"{', '.join(SAFE_KEYS)}")
    return attrs


def _index(path: str):
    """(attributes, {dataset: shape}, datasets each slab holds) of checkpoint ``path``."""
    if not os.path.isfile(path):
        raise ConfigError(f"--restart {path!r}: no such file; accepted: a checkpoint written by parslip run "
                          f"(OUT.ckpt.h5)")
    try:
        with _h5().File(path, "r") as f:
            attrs = dict(f.attrs)
            shapes = {name: f[name].shape for name in DATASETS + ("parts",) if name in f}
            held = _rows_held(f, attrs)
    except OSError as e:
        raise ConfigError(f"--restart {path!r}: not a readable HDF5 file ({e.__class__.__name__}); accepted: a "
                          f"checkpoint written by parslip run") from None
    return attrs, shapes, held


def _check_shapes(path, attrs, shapes, held, n_nodes, n_sites) -> None:
    """The checkpoint covers this lattice: every dataset of the single layout, or the parts' ranges."""
    missing = [name for name in DATASETS if name not in held and name not in initial_rows()]
    if missing:
        raise ConfigError(f"--restart {path!r}: no dataset /{missing[0]}; accepted: a checkpoint written by "
                          f"parslip run")
    if attrs.get("layout", SINGLE) == PARTS:
        have = (int(attrs.get("n_nodes", -1)), int(attrs.get("n_sites", -1)))
        if have != (n_nodes, n_sites):
            raise ConfigError(f"--restart {path!r}: {have[0]} nodes and {have[1]} interface sites, this scene "
                              f"has {n_nodes} and {n_sites}; accepted: a checkpoint of the same lattice")
        return
    want = {name: (n_nodes, cols) if cols else (n_nodes,) for name, cols in NODE_DATASETS.items()}
    want.update({name: (n_sites,) for name in BONDS.checkpoint if name in held})
    for name, shape in want.items():
        if shapes.get(name) != shape:
            raise ConfigError(f"--restart {path!r}: dataset /{name} has shape {shapes.get(name)}, this scene needs "
                              f"{shape}; accepted: a checkpoint of the same lattice")
