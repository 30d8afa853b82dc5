"""The life of one run on every rank of a communicator: the library call behind ``parslip run``.

Responsible for a run from a scene to its finished output file: reading the
scene and planning the files (rank 0 decides anything on the filesystem,
then broadcasts), starting fresh or from a checkpoint, the time loop with
its agreements, checkpoints, monitor thread and watchdog, and how it ends:

  complete       status "complete"
  stopped        SIGTERM or SIGUSR1 (Slurm's warning signals), or ``stop_after`` passed: a checkpoint
                 OUT.ckpt.h5 is written, status "checkpointed at step N"
  interrupted    Ctrl-C (SIGINT): the same checkpoint, status "interrupted at step N"
  failed         the state went non-finite or out of the halo's reach, or a write failed: status
                 "failed: ..." where it can be written, and ``RunError`` raised on every rank
  aborted        the ranks stopped agreeing (the watchdog), or a signal came while a rank was blocked:
                 the monitor thread marks the file failed and MPI_Abort ends the job with exit code 3

``parslip.run`` (the Python API) and ``cli.run`` (the command line) both call
``run_scene``; it returns an ``Outcome``.  Bad input raises ``ConfigError``
(exit 2) on every rank alike; a run that failed raises ``RunError`` (exit 3).
On several ranks an unexpected exception on one rank takes the whole job
down (MPI_Abort) rather than leave the others waiting.
"""
from __future__ import annotations

import logging
import os
import sys
import threading
import time
import traceback
import uuid
from dataclasses import dataclass, field

from .. import hooks
from ..version import __version__
from ..errors import ConfigError, RunError, WriteError

ABORT_GRACE_S = 1.0      # s: time for the launcher to forward a failing rank's traceback before MPI_Abort


@dataclass
class Outcome:
    """How a run ended, on every rank alike."""
    status: str                        # "complete", "checkpointed at step N", "interrupted at step N"
    out: str                           # the output file
    checkpoint: str | None = None      # the checkpoint to continue from, if one was written
    step: int = 0
    counters: tuple = (0, 0)           # bond breaks and re-formations over all ranks, this run
    timings: dict = field(default_factory=dict)
    size: int = 1

    @property
    def complete(self) -> bool:
        return self.status == "complete"

    @property
    def interrupted(self) -> bool:
        return self.status.startswith("interrupted")


def _logger(rank: int, size: int) -> logging.Logger:
    log = logging.getLogger("parslip")
    if not log.handlers:                      # a script that set no logging gets rank-aware lines
        from .progress import setup_logging
        setup_logging(rank, size)
    return log


class _Ranks:
    """rank, size and the one-line broadcast helpers of a communicator (None: one rank, no MPI)."""

    def __init__(self, comm):
        self.comm = comm if comm is not None and comm.Get_size() > 1 else None
        self.rank = self.comm.Get_rank() if self.comm else 0
        self.size = self.comm.Get_size() if self.comm else 1

    def decide(self, fn):
        """Run ``fn`` on rank 0 and broadcast its value, or its ConfigError, to every rank."""
        if self.comm is None:
            return fn()
        res = None
        if self.rank == 0:
            try:
                res = ("ok", fn())
            except ConfigError as e:
                res = ("err", str(e))
        res = self.comm.bcast(res, root=0)
        if res[0] == "err":
            raise ConfigError(res[1])
        return res[1]

    def agree(self, fn):
        """Run ``fn`` on every rank; if it raised ConfigError on any, raise the lowest such rank's on all."""
        try:
            fn()
            mine = None
        except ConfigError as e:
            mine = str(e)
        if self.comm is None:
            errors = [mine]
        else:
            errors = self.comm.allgather(mine)
        for e in errors:
            if e is not None:
                raise ConfigError(e)

    def sum(self, values):
        import numpy as np
        v = np.asarray(values, np.int64)
        return v if self.comm is None else self.comm.allreduce(v)


def _provenance(scene, command, run_id) -> dict:
    from ..io.output import git_commit
    import platform

    import numba
    import numpy
    return {"git_commit": git_commit(),
            "scene_file": os.path.abspath(os.fspath(scene)) if isinstance(scene, (str, os.PathLike)) else "(mapping)",
            "created_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
            "command": command or " ".join(sys.argv), "run_id": run_id, "host": platform.node(),
            "python": platform.python_version(), "numpy": numpy.__version__, "numba": numba.__version__}


def continue_command(scene, sets, out: str, ckpt: str, size: int) -> str:
    """The command line that continues a run from its checkpoint."""
    if not isinstance(scene, (str, os.PathLike)):
        return f"parslip.run(..., out={out!r}, restart={ckpt!r})"
    if isinstance(sets, dict):
        sets = [f"{k}={v!r}" if isinstance(v, str) else f"{k}={v}" for k, v in sets.items()]
    extra = "".join(f" --set {s}" for s in (sets or []))
    launch = f"mpirun -n {size} " if size > 1 else ""
    return f"{launch}parslip run {os.fspath(scene)} --out {out} --restart {ckpt}{extra}"


def run_scene(scene, *, out=None, sets=None, restart=None, overwrite: bool = False, comm=None,
              progress: bool = True, stop_after: float | None = None, watchdog: float | None = None,
              command: str | None = None) -> Outcome:
    """Run ``scene`` on every rank of ``comm`` (None: this process alone, no MPI) to ``out``.

    scene       a TOML path or a mapping of scene keys (``scene.load.load``); sets: overrides
    out         the output file (default for a path scene: out/<scene>.vtkhdf)
    restart     None, "auto" (continue OUT.ckpt.h5 if the run is not complete) or a checkpoint path
    overwrite   replace an existing output file
    progress    rank 0 logs progress lines (and says when it compiles)
    stop_after  wall seconds after which the run checkpoints and stops
    watchdog    seconds without an agreement of the ranks before the job is aborted (default: the
                scene's run.watchdog; 0 = off)
    """
    ranks = _Ranks(comm)
    try:
        return _run(ranks, scene, out, sets, restart, overwrite, progress, stop_after, watchdog, command)
    except (ConfigError, RunError, KeyboardInterrupt):
        raise
    except Exception:
        if ranks.comm is None:
            raise
        # An unexpected error on one rank must not leave the others waiting in a collective forever.
        traceback.print_exc()
        print(f"parslip {ranks.rank}/{ranks.size} ERROR: this rank failed; MPI_Abort(1) ends every rank",
              file=sys.stderr)
        sys.stderr.flush()
        time.sleep(ABORT_GRACE_S)        # the launcher forwards stderr asynchronously; Abort kills its proxies
        ranks.comm.Abort(1)
        raise


def _run(ranks, scene, out, sets, restart, overwrite, progress, stop_after, watchdog, command) -> Outcome:
    from ..io import checkpoint as ck
    from ..io.output import Output
    from ..io.plan import default_out, plan_run
    from ..io.writer_mode import writer_line
    from ..scene import advice
    from ..scene.derive import derive
    from ..scene.load import load
    from .control import CHECKPOINT, STOP, RunControl
    from .monitor import Monitor
    from .progress import Progress
    from .simulation import Simulation

    t_start = time.monotonic()
    rank, size = ranks.rank, ranks.size
    hooks.check()
    log = _logger(rank, size)
    sc = ranks.decide(lambda: load(scene, sets))
    if out is None:
        if not isinstance(scene, (str, os.PathLike)):
            raise ConfigError("out = None: a scene given as a mapping needs an output path; accepted: out='FILE'")
        out = default_out(scene)
    out = os.fspath(out)
    plan = ranks.decide(lambda: plan_run(sc, out, restart=restart, overwrite=overwrite))
    if plan.action == "done":
        log.info(f"{plan.out} is complete; nothing to do")
        return Outcome("complete", plan.out, size=size)
    out = plan.out
    if watchdog is None:
        watchdog = sc["run.watchdog"]
    if watchdog < 0:
        raise ConfigError(f"--watchdog {watchdog!r}: accepted: seconds >= 0 (0 = off)")
    omega = plan.omega or ranks.decide(lambda: (lambda s: (s.omega_max, s.omega_method))(derive(sc)))
    st = derive(sc, tuple(omega))
    if not plan.checkpoint:
        ranks.decide(lambda: _check_room(out, st))
    ranks.agree(lambda: _check_memory(st, rank, size, ranks.comm))
    sim = Simulation(st, ranks.comm, buffer_frames=sc["output.buffer_frames"],
                     buffer_events=sc["output.buffer_events"])   # ConfigError alike everywhere
    run_id = plan.run_id or ranks.decide(lambda: uuid.uuid4().hex)
    if plan.checkpoint:
        sim._phase("restore")
        arrays, attrs = ck.read(plan.checkpoint)        # every rank reads it, validated by rank 0 before
        sim.restore(arrays, attrs)
    prov = ranks.decide(lambda: _provenance(scene, command, run_id))
    prov["parslip_version"] = __version__
    writer = Output(out, sim, ranks.comm, prov, resume=run_id if plan.checkpoint else None)
    log.info(writer_line(writer.mode))
    for line in (advice.warnings(st) if rank == 0 else ()):
        log.warning(line)
    name = os.fspath(scene) if isinstance(scene, (str, os.PathLike)) else "scene"
    log.info(f"{name}: {st.lattice.n_nodes} nodes on {size} rank(s), dt = {st.dt:.5g} "
             f"({st.dt / st.dt_limit:.2f} of 2/omega_max), {st.n_steps} steps -> {out}"
             + (f"; continuing from step {sim.n} ({plan.checkpoint})" if plan.checkpoint else ""))
    prog = Progress(st, sc["output.progress_s"]) if (rank == 0 and progress) else None
    ckpt_out = ck.path_for(out)
    have_ckpt = [bool(plan.checkpoint and os.path.abspath(plan.checkpoint) == os.path.abspath(ckpt_out))]

    def on_fail(reason: str) -> str:
        """The monitor is about to abort the job: mark the output failed where this rank can."""
        if rank == 0 and writer.mode == "gather":
            done = []
            t = threading.Thread(target=lambda: done.append(writer.mark_failed(reason)), daemon=True)
            t.start()
            t.join(3.0)
            if done and done[0]:
                return f"{out} kept, status set to failed" + (f"; continue from {ckpt_out}" if have_ckpt[0] else "")
        from ..io.postmortem import mark_failed_later
        mark_failed_later(out, reason)
        return f"{out} is marked failed once every rank has ended" + \
            (f"; continue from {ckpt_out}" if have_ckpt[0] else "")

    monitor = Monitor(sim, ranks.comm, progress=prog, watchdog_s=watchdog, on_fail=on_fail, log=log)
    sim.monitor = monitor
    control = RunControl(ranks.comm, st, stop_after=stop_after, started=t_start, monitor=monitor)
    scene_toml = writer_toml(sc)
    n_start = sim.n
    timings = {}

    def checkpoint():
        sim._phase("checkpoint")
        writer.flush()                      # what the checkpoint points past is on disk first
        attrs = sim.checkpoint_attrs()
        attrs.update(scene=scene_toml, run_id=run_id, output=os.path.abspath(out))
        ck.write_collective(ranks.comm, ckpt_out, sim.checkpoint_parts(), attrs, st.lattice.n_nodes,
                            st.lattice.n_top_sites)
        have_ckpt[0] = True

    def finish_timings(t_loop, t_end, cpu_end):
        steps = sim.n - n_start
        timings.update(startup_s=t_loop - t_start - timings.get("compile_s", 0.0), loop_s=t_end - t_loop,
                       steps=steps, node_updates_per_s=steps * st.lattice.n_nodes / max(t_end - t_loop, 1e-9))
        if sim.drive_clock is not None:     # the drive alone: no start-up, no compilation, no settling
            timings.update(drive_s=t_end - sim.drive_clock[0], drive_cpu_s=cpu_end - sim.drive_clock[1],
                           drive_steps=sim.n - sim.drive_clock[2])
        writer.set_timings(timings)

    monitor.start()
    status = None
    try:
        t_c = time.monotonic()
        sim.compile()
        timings["compile_s"] = time.monotonic() - t_c
        monitor.compiled(sim.n)
        t_loop = time.monotonic()
        while True:
            action = sim.run(writer, control=control)
            if action is None:
                break
            checkpoint()
            if action == CHECKPOINT:
                log.info(f"checkpoint at step {sim.n} -> {ckpt_out}")
                continue
            status = f"{'checkpointed' if action == STOP else 'interrupted'} at step {sim.n}"
            break
        t_end, cpu_end = time.monotonic(), time.process_time()
        if status is None and (sc["checkpoint.every"] or sc["checkpoint.wall"]):
            checkpoint()                    # the end, to extend the run (drive.duration)
        sim._phase("finish")
        finish_timings(t_loop, t_end, cpu_end)
        writer.close(status or "complete")
    except RunError as e:
        msg = str(e)
        if isinstance(e, WriteError):
            msg += (f"; continue from the checkpoint {ckpt_out} with: "
                    f"{continue_command(scene, sets, out, ckpt_out, size)}" if have_ckpt[0]
                    else "; no checkpoint to continue from")
        try:
            writer.close(status=f"failed: {msg}")
        except Exception:                   # noqa: BLE001 - the disk may be full: the message matters more
            pass
        raise type(e)(msg) from None
    finally:
        monitor.stop()
        control.restore_signals()
        if prog is not None:
            prog.done()
    counts = ranks.sum(sim.counters)
    outcome = Outcome(status or "complete", out, ckpt_out if have_ckpt[0] else None, sim.n,
                      (int(counts[0]), int(counts[1])), timings, size)
    if rank == 0:
        if st.n_snapshots and status is None:
            from ..io.xdmf import write_xdmf   # snapshots as a time series for any ParaView; no collective follows
            try:
                write_xdmf(out)
            except OSError as e:
                log.warning(f"the XDMF sidecar of {out} was not written ({e})")
        steps = sim.n - n_start
        loop_s = timings.get("loop_s", 0.0)
        log.info(f"done in {loop_s:.1f} s: {steps / max(loop_s, 1e-9):,.0f} steps/s, "
                 f"{timings.get('node_updates_per_s', 0) / 1e6:.1f} M node-updates/s on {size} rank(s); "
                 f"{outcome.counters[0]} bond breaks, {outcome.counters[1]} re-formations")
        if "drive_s" in timings:
            log.info(f"drive phase {timings['drive_s']:.3f} s ({timings['drive_cpu_s']:.3f} s CPU): "
                     f"{timings['drive_steps']} steps, {timings['drive_steps'] / max(timings['drive_s'], 1e-9):,.0f} "
                     f"steps/s")
    return outcome


def _check_room(out: str, st) -> None:
    """Rank 0, before a fresh run: the output file is allocated whole when it is made, so a filesystem
    without room for it is refused now (exit 2) rather than found full at the end of the run."""
    import shutil

    from ..scene.budget import output_bytes
    need = output_bytes(st)["total"]
    try:
        free = shutil.disk_usage(os.path.dirname(os.path.abspath(out))).free
    except OSError:
        return
    if need > free:
        raise ConfigError(f"--out {out!r}: the run writes about {need / 2**20:.4g} MiB but its filesystem has "
                          f"{free / 2**20:.4g} MiB free; accepted: a path with room, or a smaller output "
                          f"(output.snapshots, output.fields = \"interface\", output.interface_dt)")


def _check_memory(st, rank: int, size: int, comm) -> None:
    """Refuse, before anything is allocated, a run whose rank would need more memory than its host has
    available: the prediction of ``scene.memory`` (within about 10 % of measured peaks) against
    MemAvailable.  Ranks that share a host each compare their own need with the whole host's memory,
    so this catches the impossible, not every squeeze."""
    from ..io.output import hdf5_mode
    from ..scene.memory import available_bytes, predict_rank
    have = available_bytes()
    if have is None:
        return
    need = predict_rank(st, rank, size, gather=hdf5_mode(size, comm) == "gather")
    if need > have:
        raise ConfigError(f"lattice: {st.lattice.n_nodes:,} nodes on {size} rank(s): rank {rank} would need about "
                          f"{need / 2**30:.3g} GiB but its host has {have / 2**30:.3g} GiB available; accepted: "
                          f"a lattice that fits (`parslip info` predicts the memory per rank) or more ranks "
                          f"spread over more hosts")


def writer_toml(scene: dict) -> str:
    from ..io.scenefile import to_toml
    return to_toml(scene)
