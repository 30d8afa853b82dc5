"""`parslip run`: one run from a scene to its output file, with checkpoints, restarts and clean stops.

Responsible for the run's life on every rank: reading the scene (rank 0
decides anything on the filesystem, then broadcasts), starting fresh or from
a checkpoint, the time loop with its progress line, and how a run ends:

  complete        the file's status is ``complete``; exit 0
  stopped         SIGTERM or SIGUSR1 (Slurm's warning signals) or --stop-after: a checkpoint
                  OUT.ckpt.h5 is written, the status is ``checkpointed at step N``, the command
                  that continues is printed; exit 0
  interrupted     Ctrl-C (SIGINT): the same checkpoint, status ``interrupted at step N``; exit 130
  failed          the state went non-finite or out of the halo's reach: status ``failed: ...``; exit 3

Every such decision is taken by all ranks at the same step: ``RunControl``
agrees on it between calls of the compiled loop, about twice a second.
"""
from __future__ import annotations

import os
import signal
import sys
import time
import uuid

import numpy as np

from ..errors import EXIT_RUN_FAILED, ConfigError

FAULT_VAR = "PARSLIP_TEST_FAIL"
CHECKPOINT, STOP, INTERRUPT = "checkpoint", "stop", "interrupt"
EXIT_INTERRUPTED = 130
# Wall time between agreements of the ranks (and progress, signals, deadlines), s.
AGREE_S = 0.5


def parse_walltime(text: str) -> float:
    """'HH:MM:SS', 'MM:SS' or seconds -> seconds."""
    try:
        parts = [float(p) for p in str(text).split(":")]
        if not 1 <= len(parts) <= 3 or any(p < 0 for p in parts):
            raise ValueError
    except ValueError:
        raise ConfigError(f"--stop-after {text!r}: accepted: a wall-clock time as HH:MM:SS, MM:SS or seconds "
                          f"(e.g. 23:30:00)") from None
    s = 0.0
    for p in parts:
        s = 60 * s + p
    return s


def parse_fault(value: str | None) -> tuple[int, int] | None:
    """``PARSLIP_TEST_FAIL="1:300"`` -> (rank 1, step 300): a test raises on that rank alone."""
    if not value:
        return None
    try:
        rank, step = (int(v) for v in value.split(":"))
        if rank < 0 or step < 0:
            raise ValueError
    except ValueError:
        raise ConfigError(f"{FAULT_VAR}={value!r}: accepted: RANK:STEP with two integers >= 0, "
                          "e.g. 1:300 (raise on rank 1 at step 300)") from None
    return rank, step


class RunControl:
    """What the ranks agree on between calls of the compiled loop: stop, checkpoint, how far to go next.

    Signals only raise a flag (a second Ctrl-C interrupts at once); rank 0's
    clock decides deadlines, the wall-clock checkpoint cadence and the size of
    the next call (about AGREE_S of work); one allreduce and one broadcast
    make every rank take the same branch at the same step.
    """

    def __init__(self, comm, setup, stop_after: float | None, started: float, progress=None):
        self.comm = comm if comm is not None and comm.Get_size() > 1 else None
        self.rank = comm.Get_rank() if comm is not None else 0
        st = setup
        self.every = int(round(st.scene["checkpoint.every"] * st.t_unit / st.dt)) if st.scene["checkpoint.every"] else 0
        self.wall_every = st.scene["checkpoint.wall"]
        self.deadline = started + stop_after if stop_after is not None else None
        self.last_ckpt = time.monotonic()
        self.fault = parse_fault(os.environ.get(FAULT_VAR))
        self.progress = progress
        self.flag = 0                           # 1: SIGINT, 2: SIGTERM or SIGUSR1
        self.chunk = None
        self.ckpt_step = -1                     # the step of the last checkpoint: never two at one step
        self._t = time.monotonic()
        self._n = None
        self._previous = {}
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGUSR1):
            try:
                self._previous[sig] = signal.signal(sig, self._on_signal)
            except ValueError:                  # not the main thread (a test harness): no signals then
                pass

    def _on_signal(self, signum, frame):
        if signum == signal.SIGINT:
            if self.flag == 1:                  # asked twice: stop now, whatever it costs
                raise KeyboardInterrupt
            self.flag = 1
        elif not self.flag:
            self.flag = 2

    def restore_signals(self):
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)

    def next_stop(self, n: int) -> int:
        """The next step at which the loop must come back (a simulated-time checkpoint)."""
        if self.every:
            return (n // self.every + 1) * self.every
        return 1 << 62

    def decide(self, sim):
        """(action or None, steps for the next call): the same on every rank."""
        n = sim.n
        if self.fault and self.fault[0] == self.rank and n >= self.fault[1]:
            raise RuntimeError(f"injected failure on rank {self.rank} at step {self.fault[1]} ({FAULT_VAR})")
        if self.progress is not None:
            self.progress.update(n)
        now = time.monotonic()
        mine = self.flag
        if self.rank == 0:
            if self.deadline is not None and now >= self.deadline:
                mine = max(mine, 2)
            if self._n is not None and n > self._n:
                rate = (n - self._n) / max(now - self._t, 1e-6)
                self.chunk = int(np.clip(rate * AGREE_S, 16, 1 << 22))
            self._t, self._n = now, n
        wall_ckpt = self.rank == 0 and self.wall_every and now - self.last_ckpt >= self.wall_every
        msg = (mine, int(bool(wall_ckpt)), self.chunk)
        if self.comm is not None:
            flags = self.comm.allreduce(mine, op=_max())
            _, wall_ckpt, chunk = self.comm.bcast(msg, root=0)
            self.chunk = chunk
        else:
            flags = mine
        if flags:
            self.ckpt_step = n
            return (INTERRUPT if flags == 1 else STOP), self.chunk
        if n != self.ckpt_step and (wall_ckpt or (self.every and n > 0 and n % self.every == 0
                                                 and n < sim.setup.n_steps)):
            self.last_ckpt = now
            self.ckpt_step = n
            return CHECKPOINT, self.chunk
        return None, self.chunk


def _max():
    from mpi4py import MPI
    return MPI.MAX


def write_checkpoint(sim, path: str, scene_toml: str, run_id: str, out: str):
    """Collective: every rank's share gathered on rank 0, written atomically (``io.checkpoint``)."""
    from ..io import checkpoint as ck
    comm = sim.comm
    st = sim.setup
    parts = sim.checkpoint_parts()
    attrs = sim.checkpoint_attrs()
    total, sites = st.lattice.n_nodes, st.lattice.n_top_sites
    arrays = {}
    for name, key, n in (("u", "gid", total), ("u_prev", "gid", total), ("drive0", "gid", total),
                         ("partner", "site", sites), ("x0", "site", sites)):
        arrays[name] = ck.gather_global(comm, parts[key], parts[name], n)
    if sim.rank == 0:
        attrs.update(scene=scene_toml, run_id=run_id, output=os.path.abspath(out))
        ck.write(path, arrays, attrs)


def continue_command(args, ckpt: str, size: int) -> str:
    """The command line that continues this run from its checkpoint."""
    sets = "".join(f" --set {s}" for s in args.set)
    launch = f"mpirun -n {size} " if size > 1 else ""
    return f"{launch}parslip run {args.scene} --out {args.out_path} --restart {ckpt}{sets}"


def cmd_run(args, comm, bcast, load, out_path) -> int:
    """`parslip run SCENE` on every rank of ``comm``; see the module docstring for how it ends."""
    from .. import analysis
    from ..engine.simulation import Simulation
    from ..errors import RunError
    from ..io import checkpoint as ck
    from ..io.output import Output, git_commit
    from ..io.writer_mode import writer_line
    from ..scene import advice
    from ..scene.derive import derive
    from ..scene.schema import to_toml
    from .progress import Progress, setup_logging

    started = time.monotonic()
    rank, size = comm.Get_rank(), comm.Get_size()
    log = setup_logging(rank, size)
    scene = bcast(lambda: load(args.scene, args.set))
    stop_after = parse_walltime(args.stop_after) if args.stop_after is not None else None
    plan = bcast(lambda: _plan(args, scene, out_path))
    if plan["action"] == "done":
        if rank == 0:
            log.info(f"{plan['out']} is complete; nothing to do")
        return 0
    out, ckpt_in = plan["out"], plan["checkpoint"]
    args.out_path = out
    omega = plan["omega"] or bcast(lambda: (lambda s: (s.omega_max, s.omega_method))(derive(scene)))
    st = derive(scene, tuple(omega))
    sim = Simulation(st, comm)              # raises ConfigError on every rank alike
    run_id = plan["run_id"] or (comm.bcast(uuid.uuid4().hex if rank == 0 else None, root=0))
    if ckpt_in:
        arrays, attrs = ck.read(ckpt_in)       # every rank reads it, validated by rank 0 before
        sim.restore(arrays, attrs)
    prov = comm.bcast({"git_commit": git_commit(), "scene_file": os.path.abspath(args.scene),
                       "created_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
                       "command": " ".join(sys.argv), "run_id": run_id} if rank == 0 else None, root=0)
    writer = Output(out, sim, comm, prov, resume=run_id if ckpt_in else None)
    log.info(writer_line(writer.mode))
    for line in (advice.warnings(st) if rank == 0 else ()):
        log.warning(line)
    log.info(f"{args.scene}: {st.lattice.n_nodes} nodes on {size} rank(s), dt = {st.dt:.5g} "
             f"({st.dt / st.dt_limit:.2f} of 2/omega_max), {st.n_steps} steps -> {out}"
             + (f"; continuing from step {sim.n} ({ckpt_in})" if ckpt_in else ""))
    prog = Progress(st, scene["output.progress_s"], enabled=(rank == 0 and not args.quiet))
    control = RunControl(comm, st, stop_after, started, prog)
    ckpt_out = ck.path_for(out)
    scene_toml = to_toml(scene)
    n_start = sim.n
    t0 = time.monotonic()
    try:
        while True:
            action = sim.run(writer, control=control)
            if action is None:
                break
            writer.flush()                  # what the checkpoint points past is on disk first
            write_checkpoint(sim, ckpt_out, scene_toml, run_id, out)
            if action == CHECKPOINT:
                log.info(f"checkpoint at step {sim.n} -> {ckpt_out}")
                continue
            how = "checkpointed" if action == STOP else "interrupted"
            writer.close(status=f"{how} at step {sim.n}")
            prog.done()
            if rank == 0:
                print(f"parslip: {how} at step {sim.n}; output kept in {out}; continue with:\n"
                      f"  {continue_command(args, ckpt_out, size)}", file=sys.stderr)
            return 0 if action == STOP else EXIT_INTERRUPTED
    except RunError as e:
        writer.close(status=f"failed: {e}")
        prog.done()
        if rank == 0:
            print(f"parslip: run failed: {e}", file=sys.stderr)
        return EXIT_RUN_FAILED
    finally:
        control.restore_signals()
    prog.done()
    t_end, cpu_end = time.monotonic(), time.process_time()
    wall = t_end - t0
    if scene["checkpoint.every"] or scene["checkpoint.wall"]:
        write_checkpoint(sim, ckpt_out, scene_toml, run_id, out)   # the end, to extend the run (drive.duration)
    writer.close("complete")
    counts = comm.reduce(sim.counters.copy(), root=0) if size > 1 else sim.counters
    if rank == 0 and st.n_snapshots:    # snapshots as a time series for any ParaView (io/xdmf.py); no collective follows
        from ..io.xdmf import write_xdmf
        write_xdmf(out)
    if rank == 0:
        steps = sim.n - n_start
        ups = steps * st.lattice.n_nodes / max(wall, 1e-9)
        log.info(f"done in {wall:.1f} s: {steps / max(wall, 1e-9):,.0f} steps/s, {ups / 1e6:.1f} M node-updates/s "
                 f"on {size} rank(s); {int(counts[0])} bond breaks, {int(counts[1])} re-formations")
        if sim.drive_clock is not None:     # the drive alone: no start-up, no compilation, no settling
            drive, cpu = t_end - sim.drive_clock[0], cpu_end - sim.drive_clock[1]
            n_drive = sim.n - max(n_start, st.n_drive_start)
            log.info(f"drive phase {drive:.3f} s ({cpu:.3f} s CPU): {n_drive} steps, "
                     f"{n_drive / max(drive, 1e-9):,.0f} steps/s")
        iface = analysis.load_interface(out)
        print(analysis.summary(iface))
        png = os.path.splitext(out)[0] + "_spacetime.png"
        if not args.no_png and analysis.spacetime_png(
                iface, png, f"{os.path.basename(args.scene)}: {scene['drive.mode']}, v0/c_r = {scene['drive.v0']:g}"):
            log.info(f"wrote {out} and {png}")
        else:
            log.info(f"wrote {out}")
    return 0


def _plan(args, scene, out_path) -> dict:
    """Rank 0: fresh run or restart, which files; a bad request is a ConfigError (exit 2)."""
    import h5py

    from ..io import checkpoint as ck
    from ..model.lattice import Lattice
    if not args.restart:
        return {"action": "run", "out": out_path(args), "checkpoint": None, "omega": None, "run_id": None}
    out = out_path(args, must_exist=True) if args.restart != "auto" else out_path(args, may_exist=True)
    ckpt = ck.path_for(out) if args.restart == "auto" else args.restart
    if args.restart == "auto":
        if os.path.exists(out):
            try:
                with h5py.File(out, "r") as f:
                    if str(f.attrs.get("status", "")) == "complete":
                        return {"action": "done", "out": out}
            except OSError:
                pass
        if not os.path.exists(ckpt):
            return {"action": "run", "out": out, "checkpoint": None, "omega": None, "run_id": None}
    lat = Lattice(scene["lattice.top_rows"], scene["lattice.top_cols"], scene["lattice.bottom_rows"],
                  scene["lattice.bottom_cols"], scene["interface.delta0"], scene["lattice.substrate"])
    attrs = ck.validate(ckpt, scene, lat.n_nodes, lat.n_top_sites)
    if not os.path.exists(out):
        raise ConfigError(f"--out {out!r}: no such file; a restart appends to the output file of the run that "
                          f"wrote {ckpt!r}; accepted: that file (--out)")
    return {"action": "run", "out": out, "checkpoint": ckpt, "omega": (float(attrs["omega_max"]),
                                                                         str(attrs["omega_method"])),
            "run_id": str(attrs["run_id"])}


