"""Checkpoints: everything a run needs to continue exactly, written atomically, checked before use.

A checkpoint is one HDF5 file holding, by global id (so any rank count can
read it back):

  /u, /u_prev     float [nodes, 2]   displacements u(n) and u(n-1), in a (the state's float type)
  /drive0         float [nodes]      x displacement of each node when the drive started (driven nodes)
  /drive_force    float [nodes]      the x-force the drive applied to each driven node in the last step
  /partner, /x0, ...  [sites]      the bond state of every interface site, one dataset per row the bond
                                    table saves (``model.interface.BOND_TABLE``: the substrate column bonded
                                    to, the rest offset x0, the healing candidate and clock, the site's kx,
                                    ky and delta_b), each in the dtype the table gives
  root attributes  the step n, the resolved scene (TOML), omega_max and dt, the output cursor (frames and
                   snapshots written, bond events written), the bond event counters, the run id shared with the output file,
                   the rank count that wrote it, and ``complete`` = 1, set last.

Writing: rank 0 gathers and writes ``PATH.tmp``, flushes and fsyncs it, then
renames it over ``PATH``: a process killed at any moment leaves the previous
checkpoint whole.  Reading: ``validate`` refuses, with one line naming what
is wrong (exit 2), a file that is not a complete parslip checkpoint, or one
from another scene, except for the keys ``SAFE_KEYS`` that may change on a
restart (duration, output cadence, progress, checkpoint cadence).  A key the
checkpoint's scene lacks (added since) counts as its ``IMPLIED`` value.
"""
from __future__ import annotations

import os

import numpy as np

from ..errors import ConfigError
from ..model.interface import ADDED_ROWS, BONDS

FORMAT = "parslip checkpoint 3"          # 2: with drive_force; 3: with events_written
SAFE_KEYS = ("drive.duration", "output.interface_dt", "output.snapshots", "output.progress_s",
             "output.buffer_frames", "output.buffer_events", "checkpoint.every", "checkpoint.wall",
             "interface.slip_reach", "run.watchdog")
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


def path_for(out: str) -> str:
    """The checkpoint that belongs to output file ``out``: OUT.ckpt.h5."""
    return out + ".ckpt.h5"


_written = 0


def write(path: str, parts: dict, attrs: dict) -> None:
    """Write a checkpoint (rank 0 only): ``parts`` are whole arrays in global order.

    For the tests of atomicity, the hook ``kill_in_checkpoint=K`` (``parslip.hooks``) kills this
    process with SIGKILL halfway through writing its K-th checkpoint.
    """
    import h5py

    from .. import hooks
    global _written
    _written += 1
    kill = hooks.get("kill_in_checkpoint") == _written
    tmp = path + ".tmp"
    with h5py.File(tmp, "w") as f:
        for name in DATASETS:
            f.create_dataset(name, data=parts[name])
            if kill:
                f.flush()
                import signal
                os.kill(os.getpid(), signal.SIGKILL)
        for k, v in attrs.items():
            f.attrs[k] = v
        f.attrs["format"] = FORMAT
        f.flush()
        f.attrs["complete"] = 1
    fd = os.open(tmp, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
    os.replace(tmp, path)
    try:                                  # the rename itself survives a crash once the folder is synced
        dfd = os.open(os.path.dirname(os.path.abspath(path)), os.O_RDONLY)
        try:
            os.fsync(dfd)
        finally:
            os.close(dfd)
    except OSError:
        pass


def read(path: str) -> tuple[dict, dict]:
    """(arrays, attributes) of a checkpoint that ``validate`` accepted."""
    import h5py
    with h5py.File(path, "r") as f:
        # A bond row added to the table since the checkpoint was written starts at zero (``ADDED_ROWS``).
        n_sites = f["partner"].shape[0]
        return {name: f[name][...] if name in f else np.zeros(n_sites) for name in DATASETS}, dict(f.attrs)


def validate(path: str, scene: dict, n_nodes: int, n_sites: int) -> dict:
    """Check a checkpoint before use; returns its attributes.  Raises ConfigError (exit 2) with one line."""
    import h5py

    from .scenefile import loads
    if not os.path.isfile(path):
        raise ConfigError(f"--restart {path!r}: no such file; accepted: a checkpoint written by parslip run "
                          f"(OUT.ckpt.h5)")
    try:
        with h5py.File(path, "r") as f:
            attrs = dict(f.attrs)
            shapes = {name: f[name].shape for name in DATASETS if name in f}
    except OSError as e:
        raise ConfigError(f"--restart {path!r}: not a readable HDF5 file ({e.__class__.__name__}); accepted: a "
                          f"checkpoint written by parslip run") from None
    if attrs.get("format") != FORMAT:
        old = str(attrs.get("format", "")).startswith("parslip checkpoint")
        raise ConfigError(f"--restart {path!r}: " + (f"a checkpoint of an older format ({attrs.get('format')!r}); "
                                                     f"accepted: {FORMAT!r}, written by this version of parslip run"
                                                     if old else "not a parslip checkpoint; accepted: a file written "
                                                     "by parslip run as OUT.ckpt.h5"))
    if int(attrs.get("complete", 0)) != 1:
        raise ConfigError(f"--restart {path!r}: incomplete checkpoint (the writer stopped before finishing); "
                          f"accepted: a complete checkpoint")
    want = {name: (n_nodes, cols) if cols else (n_nodes,) for name, cols in NODE_DATASETS.items()}
    want.update({name: (n_sites,) for name in BONDS.checkpoint})
    for name, shape in want.items():
        if name in ADDED_ROWS and name not in shapes:
            continue                     # written before the row existed: it starts at zero (``read``)
        if shapes.get(name) != shape:
            raise ConfigError(f"--restart {path!r}: dataset /{name} has shape {shapes.get(name)}, this scene needs "
                              f"{shape}; accepted: a checkpoint of the same lattice")
    saved = loads(str(attrs["scene"]))
    for key in sorted(set(saved) | set(scene)):
        if key in SAFE_KEYS:
            continue
        if saved.get(key, IMPLIED.get(key)) != scene.get(key):
            raise ConfigError(f"--restart {path!r}: {key} = {scene.get(key)!r} but the checkpoint was written with "
                              f"{saved.get(key, IMPLIED.get(key))!r}; accepted: the same scene, except "
                              f"{', '.join(SAFE_KEYS)}")
    return attrs


def write_collective(comm, path: str, parts: dict, attrs: dict, n_nodes: int, n_sites: int) -> None:
    """Collective: every rank's share (``parts``: arrays by global node id "gid" or site index "site",
    from ``Simulation.checkpoint_parts``) gathered on rank 0, which writes them atomically (``write``)."""
    arrays = {name: gather_global(comm, parts["gid"], parts[name], n_nodes) for name in NODE_DATASETS}
    for name in BONDS.checkpoint:
        rows = parts[name] if BONDS.dtypes[name] is None else parts[name].astype(BONDS.dtypes[name])
        arrays[name] = gather_global(comm, parts["site"], rows, n_sites)
    err = None
    if comm is None or comm.Get_rank() == 0:
        try:
            write(path, arrays, attrs)
        except OSError as e:
            err = f"cannot write the checkpoint {path} ({e.__class__.__name__}: {e})"
    if comm is not None and comm.Get_size() > 1:
        err = comm.bcast(err, root=0)               # every rank fails alike, none waits for another
    if err:
        from ..errors import WriteError
        raise WriteError(err, path=path)


def gather_global(comm, gid: np.ndarray, values: np.ndarray, total: int) -> np.ndarray | None:
    """Values held by global id on every rank, assembled on rank 0 (None elsewhere)."""
    if comm is None:
        out = np.zeros((total,) + values.shape[1:], values.dtype)
        out[gid] = values
        return out
    parts = comm.gather((gid, values), root=0)
    if comm.Get_rank() != 0:
        return None
    out = np.zeros((total,) + values.shape[1:], values.dtype)
    for g, v in parts:
        out[g] = v
    return out
