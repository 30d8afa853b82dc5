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
from ..parallel import collective
from ..parallel.exchange import describe as describe_exchange
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
        return collective.decide(self.comm, fn)

    def agree(self, fn):
        """Run ``fn`` on every rank; if it raised ConfigError on any, raise the lowest such rank's on all."""
        collective.agree(self.comm, fn)

    def sum(self, values):
        import numpy as np
        v = np.asarray(values, np.int64)
        return v if self.comm is None else self.comm.allreduce(v)


def _provenance(scene, command, run_id) -> dict:
    from ..version import git_commit
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
        job = Job(ranks, scene, sets=sets, command=command)
        if not job.prepare(out, restart, overwrite, progress, stop_after, watchdog):
            return job.outcome()
        return job.execute()
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


class Job:
    """One run on every rank of a communicator, in named steps, each collective:

    prepare    the scene read and the files planned (rank 0 decides, every rank learns), the set-up
               derived, room and memory checked, the state built fresh or restored from a checkpoint,
               the output opened, the monitor and the run control made; False when the output is
               already complete and there is nothing to do
    execute    start the monitor, then ``loop`` and ``finish``; a failed run marks its output failed
               and raises ``RunError`` on every rank; the monitor and the signals are always restored
    loop       compile (timed apart), then advance until the end or an agreed stop, writing each
               checkpoint the ranks agreed on (``checkpoint``)
    finish     the end's checkpoint when checkpoints are on (to extend the run), the timings, the
               output's status; then on rank 0 the XDMF sidecar and the summary lines
    """

    def __init__(self, ranks, scene, sets=None, command: str | None = None):
        self.ranks, self.scene, self.sets, self.command = ranks, scene, sets, command
        self.t_start = time.monotonic()
        self.log = _logger(ranks.rank, ranks.size)
        self.status = None                 # None while running or complete; else "checkpointed at step N", ...
        self.timings = {}
        self.have_checkpoint = False       # a checkpoint of this run exists to continue from
        self.prog = self.monitor = self.control = self.writer = None

    # ------------------------------------------------------------------ prepare --
    def prepare(self, out, restart, overwrite, progress, stop_after, watchdog) -> bool:
        """Everything before the first step; False when the output is complete already."""
        from ..io.run_files import plan_run
        hooks.check()
        ranks = self.ranks
        self.sc = sc = ranks.decide(lambda: _load(self.scene, self.sets))
        out = _output_path(self.scene, out)
        plan = ranks.decide(lambda: plan_run(sc, out, restart=restart, overwrite=overwrite))
        self.out, self.plan = plan.out, plan
        if plan.action == "done":
            self.log.info(f"{plan.out} is complete; nothing to do")
            self.status = "complete"
            return False
        watchdog = sc["run.watchdog"] if watchdog is None else watchdog
        if watchdog < 0:
            raise ConfigError(f"--watchdog {watchdog!r}: accepted: seconds >= 0 (0 = off)")
        self.st = st = self._setup()
        self.sim = self._simulation()
        self.run_id = plan.run_id or ranks.decide(lambda: uuid.uuid4().hex)
        self._open_output()
        self._announce()
        self.prog = _progress(st, sc) if (ranks.rank == 0 and progress) else None
        self._make_control(watchdog, stop_after)
        return True

    def _setup(self):
        """The derived set-up, its omega_max computed once (rank 0, or the checkpoint's) for every rank."""
        from ..scene.derive import derive
        ranks, sc, plan = self.ranks, self.sc, self.plan
        omega = plan.omega or ranks.decide(lambda: (lambda s: (s.omega_max, s.omega_method))(derive(sc)))
        st = derive(sc, tuple(omega))
        if not plan.checkpoint:
            ranks.decide(lambda: _check_room(self.out, st))
        ranks.agree(lambda: _check_memory(st, ranks.rank, ranks.size, ranks.comm))
        return st

    def _simulation(self):
        """This rank's simulation, fresh or at the checkpoint's step (every rank reads its own slab of the
        checkpoint, which rank 0 validated when it planned the run; a part missing on any rank is bad input
        on all)."""
        from ..io import checkpoint as ck
        from .simulation import Simulation
        sc = self.sc
        sim = Simulation(self.st, self.ranks.comm, buffer_frames=sc["output.buffer_frames"],
                         buffer_events=sc["output.buffer_events"])   # ConfigError alike everywhere
        self.ckpt_out = ck.path_for(self.out)
        self.first_call = None
        if self.plan.checkpoint:
            # Compiled (once per job) before the restore, whose halo exchange would otherwise compile on every rank.
            self.first_call = self._compile(sim)
            got = []
            self.ranks.agree(lambda: got.append(ck.read(self.plan.checkpoint, *sim.slab_ranges(), sim.dtype)))
            sim.restore(*got[0])
            self.have_checkpoint = os.path.abspath(self.plan.checkpoint) == os.path.abspath(self.ckpt_out)
        self.n_start = sim.n
        return sim

    def _open_output(self):
        from ..io.output import Output
        from ..io.writer_mode import writer_line
        prov = self.ranks.decide(lambda: _provenance(self.scene, self.command, self.run_id))
        prov["parslip_version"] = __version__
        self.writer = Output(self.out, self.sim.output_spec(), self.ranks.comm, prov,
                             resume=self.run_id if self.plan.checkpoint else None)
        self.log.info(writer_line(self.writer.mode))

    def _announce(self):
        """Rank 0's advice on the scene; every rank's line of what runs where."""
        from ..scene import advice
        st, log, size = self.st, self.log, self.ranks.size
        for line in (advice.warnings(st) if self.ranks.rank == 0 else ()):
            log.warning(line)
        name = os.fspath(self.scene) if isinstance(self.scene, (str, os.PathLike)) else "scene"
        log.info(f"{name}: {st.lattice.n_nodes} nodes on {size} rank(s), dt = {st.dt:.5g} "
                 f"({st.dt / st.dt_limit:.2f} of the stability limit), {st.n_steps} steps -> {self.out}"
                 + (f"; continuing from step {self.sim.n} ({self.plan.checkpoint})" if self.plan.checkpoint else ""))
        said = describe_exchange(self.sim.plan, self.ranks.comm)
        if said:
            log.info(said)

    def _make_control(self, watchdog, stop_after):
        from .control import RunControl
        from .monitor import Monitor
        self.monitor = Monitor(self.sim, self.ranks.comm, progress=self.prog, watchdog_s=watchdog,
                               on_fail=self._on_fail, log=self.log)
        self.sim.monitor = self.monitor
        self.control = RunControl(self.ranks.comm, self.st, stop_after=stop_after, started=self.t_start,
                                  monitor=self.monitor)

    def _on_fail(self, reason: str) -> str:
        """The monitor is about to abort the job: mark the output failed where this rank can."""
        out, more = self.out, (f"; continue from {self.ckpt_out}" if self.have_checkpoint else "")
        if self.ranks.rank == 0 and self.writer.mode == "gather":
            done = []
            t = threading.Thread(target=lambda: done.append(self.writer.mark_failed(reason)), daemon=True)
            t.start()
            t.join(3.0)
            if done and done[0]:
                return f"{out} kept, status set to failed" + more
        from ..io.postmortem import mark_failed_later
        mark_failed_later(out, reason)
        return f"{out} is marked failed once every rank has ended" + more

    # ------------------------------------------------------------ execute --
    def execute(self) -> Outcome:
        """``loop`` and ``finish`` under the monitor; a failed run marks the output and raises on every rank."""
        self.monitor.start()
        try:
            self.loop()
            self.finish()
        except RunError as e:
            raise self._failed(e) from None
        finally:
            self.monitor.stop()
            self.control.restore_signals()
            if self.prog is not None:
                self.prog.done()
        outcome = self.outcome()
        self._memory_line()
        self.sim.release()          # collective, as the lines above: a sweep's runs leave no window behind
        if self.ranks.rank == 0:
            self._report(outcome)
        return outcome

    def _memory_line(self):
        """Collective: each rank's peak resident memory so far (getrusage), gathered in one collective;
        rank 0 logs ``memory: peak RSS MiB rank 0 X, median Y, max Z``."""
        import resource

        import numpy as np
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / (2.0 ** 20 if sys.platform == "darwin" else 1024.0)
        peaks = [peak] if self.ranks.comm is None else self.ranks.comm.gather(peak, root=0)
        if self.ranks.rank == 0:
            self.log.info(f"memory: peak RSS MiB rank 0 {peaks[0]:.1f}, median {float(np.median(peaks)):.1f}, "
                          f"max {max(peaks):.1f}")

    def _compile(self, sim):
        """The loop's first call (``Simulation.compile``), timed."""
        t_c = time.monotonic()
        first = sim.compile()
        self.timings["compile_s"] = time.monotonic() - t_c
        return first

    def loop(self):
        """Compile, then advance to the end or to an agreed stop, writing the agreed checkpoints."""
        from .control import CHECKPOINT, STOP
        sim = self.sim
        said = (self.first_call or self._compile(sim)).line()
        if said and self.ranks.rank == 0:
            self.log.info(said)
        self.monitor.compiled(sim.n)
        self.t_loop = time.monotonic()
        while True:
            action = sim.run(self.writer, control=self.control)
            if action is None:
                break
            self.checkpoint()
            if action == CHECKPOINT:
                self.log.info(f"checkpoint at step {sim.n} -> {self.ckpt_out}")
                continue
            self.status = f"{'checkpointed' if action == STOP else 'interrupted'} at step {sim.n}"
            break
        self.t_end, self.cpu_end = time.monotonic(), time.process_time()

    def checkpoint(self):
        """Write OUT.ckpt.h5 (collective), after the output holds everything it points past."""
        from ..io import checkpoint as ck
        self.monitor.phase("checkpoint")
        self.writer.flush()                 # what the checkpoint points past is on disk first
        attrs = self.sim.checkpoint_attrs()
        attrs.update(scene=writer_toml(self.sc), run_id=self.run_id, output=os.path.abspath(self.out))
        # Each rank writes its own slab: collectively into one file where the output goes through mpio,
        # else into a part file of its own beside an index.
        ck.write(self.ranks.comm, self.ckpt_out, self.sim.checkpoint_slab(), attrs, self.sim.checkpoint_table(),
                 collective=self.writer.mode == "mpio")
        self.have_checkpoint = True

    def finish(self):
        """The end's checkpoint (to extend the run with drive.duration), the timings and the status."""
        sc = self.sc
        if self.status is None and (sc["checkpoint.every"] or sc["checkpoint.wall"]):
            self.checkpoint()
        self.monitor.phase("finish")
        self._timings()
        held = self.sim.hold.output_attrs()
        if held:                            # the same on every rank: the scene's
            self.writer.set_attrs(held)
        self.writer.close(self.status or "complete")

    def _timings(self):
        sim, st, tm = self.sim, self.st, self.timings
        steps = sim.n - self.n_start
        loop_s = self.t_end - self.t_loop
        tm.update(startup_s=self.t_loop - self.t_start - tm.get("compile_s", 0.0), loop_s=loop_s, steps=steps,
                  node_updates_per_s=steps * st.lattice.n_nodes / max(loop_s, 1e-9))
        if sim.drive_clock is not None:     # the drive alone: no start-up, no compilation, no settling
            tm.update(drive_s=self.t_end - sim.drive_clock[0], drive_cpu_s=self.cpu_end - sim.drive_clock[1],
                      drive_steps=sim.n - sim.drive_clock[2])
        self.writer.set_timings(tm)

    def _failed(self, e: RunError) -> RunError:
        """A run that failed: its output marked failed (as far as the disk lets), the error to raise."""
        msg = str(e)
        if isinstance(e, WriteError):
            msg += (f"; continue from the checkpoint {self.ckpt_out} with: "
                    f"{continue_command(self.scene, self.sets, self.out, self.ckpt_out, self.ranks.size)}"
                    if self.have_checkpoint else "; no checkpoint to continue from")
        try:
            self.writer.close(status=f"failed: {msg}")
        except Exception:                   # noqa: BLE001 - the disk may be full: the message matters more
            pass
        return type(e)(msg)

    # ------------------------------------------------------------ the end --
    def outcome(self) -> Outcome:
        """How the run ended, the same on every rank (the bond counters summed over the ranks)."""
        if self.writer is None:            # nothing ran: the output was complete already
            return Outcome("complete", self.out, size=self.ranks.size)
        counts = self.ranks.sum(self.sim.counters)
        return Outcome(self.status or "complete", self.out, self.ckpt_out if self.have_checkpoint else None,
                       self.sim.n, (int(counts[0]), int(counts[1])), self.timings, self.ranks.size)

    def _report(self, outcome: Outcome):
        """Rank 0: the XDMF sidecar of a complete run with snapshots (no collective follows), the rates."""
        log, tm = self.log, self.timings
        if self.st.n_snapshots and self.status is None:
            from ..io.xdmf import write_xdmf
            try:
                write_xdmf(self.out)
            except OSError as e:
                log.warning(f"the XDMF sidecar of {self.out} was not written ({e})")
        steps, loop_s = self.sim.n - self.n_start, tm.get("loop_s", 0.0)
        log.info(f"done in {loop_s:.1f} s: {steps / max(loop_s, 1e-9):,.0f} steps/s, "
                 f"{tm.get('node_updates_per_s', 0) / 1e6:.1f} M node-updates/s on {self.ranks.size} rank(s); "
                 f"{outcome.counters[0]} bond breaks, {outcome.counters[1]} re-formations")
        if "drive_s" in tm:
            log.info(f"drive phase {tm['drive_s']:.3f} s ({tm['drive_cpu_s']:.3f} s CPU): "
                     f"{tm['drive_steps']} steps, {tm['drive_steps'] / max(tm['drive_s'], 1e-9):,.0f} steps/s")
        if self.sim.params.follow:
            d = self.sim.layout.reach.drift
            log.info(f"interface halo: {self.sim.rebuilds} rebuilds (the block's slabs stand {d.shift} columns "
                     f"ahead of the substrate's; halos of {max(self.sim.layout.reach.top)} and "
                     f"{max(self.sim.layout.reach.bottom)} columns)")


def _load(scene, sets):
    from ..scene.load import load
    return load(scene, sets)


def _output_path(scene, out) -> str:
    """``out``, or the default beside a scene file; a scene given as a mapping must name its output."""
    from ..io.run_files import default_out
    if out is None:
        if not isinstance(scene, (str, os.PathLike)):
            raise ConfigError("out = None: a scene given as a mapping needs an output path; accepted: out='FILE'")
        out = default_out(scene)
    return os.fspath(out)


def _progress(st, sc):
    from .progress import Progress
    return Progress(st, sc["output.progress_s"])


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
