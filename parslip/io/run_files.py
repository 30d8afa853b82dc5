"""Which files a run reads and writes: a fresh output, a restart from a checkpoint, or nothing to do.

Responsible for the decisions on the filesystem before a run starts, made by
rank 0 alone and then broadcast (``engine.runner``): the output path (new
unless overwriting; a folder is made; it must be writable), and for a
restart the checkpoint (validated against the scene, ``io.checkpoint``) and
the output file it appends to.  A bad request is a ``ConfigError`` (exit 2)
that names the argument, the value and what is accepted.
"""
from __future__ import annotations

import os
from dataclasses import dataclass

from ..errors import ConfigError
from . import checkpoint as ck
from .contract import read_status


@dataclass(frozen=True)
class RunPlan:
    action: str                       # "run" or "done" (a complete run asked to continue with restart="auto")
    out: str
    checkpoint: str | None = None     # continue from this checkpoint
    omega: tuple | None = None        # (omega_max, method) of the checkpointed run
    run_id: str | None = None         # the checkpointed run's id, shared with its output file


def default_out(scene_path) -> str:
    """out/<scene name>.vtkhdf"""
    return os.path.join("out", os.path.splitext(os.path.basename(str(scene_path)))[0] + ".vtkhdf")


def output_path(out: str, *, overwrite: bool = False, must_exist: bool = False, may_exist: bool = False) -> str:
    """The output file: new unless ``overwrite``, existing for a restart; its folder made and writable."""
    out = os.fspath(out)
    if os.path.isdir(out):
        raise ConfigError(f"--out {out!r}: is a directory; accepted: a file path")
    if must_exist:
        if not os.path.isfile(out):
            raise ConfigError(f"--out {out!r}: no such file; a restart appends to the output file of the run that "
                              f"wrote the checkpoint; accepted: that file")
        return out
    if os.path.exists(out) and not (overwrite or may_exist):
        raise ConfigError(f"--out {out!r}: exists; accepted: a new path, --overwrite to replace it, or "
                          f"--restart to continue it")
    d = os.path.dirname(out)
    try:
        if d:
            os.makedirs(d, exist_ok=True)
        if not os.access(d or ".", os.W_OK):
            raise PermissionError
    except OSError:
        raise ConfigError(f"--out {out!r}: cannot write in {d or '.'!r}; accepted: a writable path") from None
    return out


def plan_run(scene: dict, out: str, *, restart: str | None = None, overwrite: bool = False) -> RunPlan:
    """Rank 0: fresh run or restart, which files.  ``restart`` is None, "auto" or a checkpoint path."""
    import h5py

    from ..model.lattice import Lattice
    if not restart:
        return RunPlan("run", output_path(out, overwrite=overwrite))
    restart = os.fspath(restart)
    auto = restart == "auto"
    out = output_path(out, may_exist=True) if auto else output_path(out, must_exist=True)
    ckpt = ck.path_for(out) if auto else restart
    if auto:
        if os.path.exists(out):
            try:
                with h5py.File(out, "r") as f:
                    if read_status(f) == "complete":
                        return RunPlan("done", out)
            except OSError:
                pass
        if not os.path.exists(ckpt):
            return RunPlan("run", output_path(out, overwrite=True))
    lat = Lattice(scene["lattice.top_rows"], scene["lattice.top_cols"], scene["lattice.bottom_rows"],
                  scene["lattice.bottom_cols"], scene["interface.delta0"], scene["lattice.substrate"])
    attrs = ck.validate(ckpt, scene, lat.n_nodes, lat.n_top_sites)
    if not os.path.exists(out):
        raise ConfigError(f"--out {out!r}: no such file; a restart appends to the output file of the run that "
                          f"wrote {ckpt!r}; accepted: that file (--out)")
    return RunPlan("run", out, ckpt, (float(attrs["omega_max"]), str(attrs["omega_method"])), str(attrs["run_id"]))
