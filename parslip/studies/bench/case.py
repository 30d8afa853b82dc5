"""One benchmark case: a scene scaled to contact length l, run on the ranks of this MPI job.

    mpiexec -n R python -m parslip.studies.bench.case --l 500 --mode shear --precision float64 --seconds 4

Measures, in this order: imports, deriving the scene (omega_max), building
the rank's state, the first compiled call (loading the compiled loop from
numba's cache, or compiling it), then a warm-up and ``--seconds`` of the
drive phase on the whole run path (interface bonds, damping, the driven
face, interface frames and bond events written at the scene's cadence to
a scratch file).
The load is applied at once (no ramp or settle), so timing starts in the
drive.  Prints one JSON line on rank 0.
"""
from __future__ import annotations

import time

T0 = time.perf_counter()

import argparse  # noqa: E402
import json  # noqa: E402
import os  # noqa: E402
import resource  # noqa: E402
import tempfile  # noqa: E402

from mpi4py import MPI  # noqa: E402

from ...engine import loop as L  # noqa: E402
from ...engine.simulation import Simulation  # noqa: E402
from ...errors import ConfigError  # noqa: E402
from ...io.output import Output  # noqa: E402
from ...parallel import collective  # noqa: E402
from ...scene.derive import derive  # noqa: E402
from ...scene.load import load, overrides  # noqa: E402

T_IMPORTS = time.perf_counter() - T0


def scene_at(l: int, mode: str, precision: str, extra=()) -> dict:
    """The paper's geometry scaled to contact length l (top 10 x 100, substrate 20 x 300 at l = 100)."""
    s = l / 100
    return load({}, dict([("lattice.top_rows", max(2, round(10 * s))), ("lattice.top_cols", l),
                          ("lattice.bottom_rows", max(2, round(20 * s))), ("lattice.bottom_cols", 3 * l),
                          ("drive.mode", mode), ("drive.v0", 1e-3 if mode != "shear" else 1e-4),
                          ("load.ramp", 0.0), ("load.settle", 0.0), ("output.snapshots", 0),
                          ("time.precision", precision), *extra]))


class _TimedWriter:
    """Output that also times its interface-frame and bond-event writes."""

    def __init__(self, out):
        self.out, self.seconds, self.frames = out, 0.0, 0
        self.event_seconds, self.events = 0.0, 0

    def interface_frames(self, k0, count, frames, *args, **kw):
        t = time.perf_counter()
        self.out.interface_frames(k0, count, frames, *args, **kw)
        self.seconds += time.perf_counter() - t
        self.frames += count

    def interface_events(self, k0, *args):
        t = time.perf_counter()
        total = self.out.interface_events(k0, *args)
        self.event_seconds += time.perf_counter() - t
        self.events += total - k0
        return total

    def snapshot(self, *a):
        self.out.snapshot(*a)

    def __getattr__(self, name):
        return getattr(self.out, name)          # whatever else the engine asks of its writer (follow, ...)


def _scratch_folder() -> str:
    """A new folder for the case's output file, or a ConfigError every rank raises (``collective.decide``)."""
    try:
        return tempfile.mkdtemp(prefix="parslip-bench-")
    except OSError as e:
        raise ConfigError(f"TMPDIR {tempfile.gettempdir()!r}: cannot make a scratch folder there ({e}); "
                          f"accepted: a writable folder") from None


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--l", type=int, default=100)
    p.add_argument("--mode", default="shear")
    p.add_argument("--precision", default="float64")
    p.add_argument("--seconds", type=float, default=4.0)
    p.add_argument("--set", action="append", default=[])
    a = p.parse_args()
    comm = MPI.COMM_WORLD
    rank, size = comm.Get_rank(), comm.Get_size()
    extra = overrides(a.set)                  # KEY=VALUE, the value a TOML literal (as `parslip run --set`)
    t = time.perf_counter()
    sc = scene_at(a.l, a.mode, a.precision, extra)
    st = collective.decide(comm, lambda: derive(sc))
    t_derive = time.perf_counter() - t
    t = time.perf_counter()
    sim = Simulation(st, comm)
    t_build = time.perf_counter() - t
    t = time.perf_counter()
    sim.run(until=1)                          # loads (or compiles) the compiled loop
    t_first = time.perf_counter() - t
    tmp = collective.decide(comm, _scratch_folder)
    out = Output(os.path.join(tmp, "bench.vtkhdf"), sim.output_spec(), comm)
    writer = _TimedWriter(out)
    n_nodes = st.lattice.n_nodes
    # Warm-up, and a step count for the requested time (agreed by all ranks).
    t = time.perf_counter()
    sim.run(writer, until=sim.n + 200)
    per_step = comm.allreduce(time.perf_counter() - t, op=MPI.MAX) / 200
    steps = int(max(200, a.seconds / per_step))
    sim.diag.timers[:] = 0
    c0 = sim.counters.copy()
    writer.seconds, writer.frames = 0.0, 0
    writer.event_seconds, writer.events = 0.0, 0
    comm.Barrier()
    t = time.perf_counter()
    sim.run(writer, until=sim.n + steps)
    comm.Barrier()
    wall = time.perf_counter() - t
    out.close()
    tm = sim.diag.timers.astype(float)
    samples = max(tm[L.T_SAMPLES], 1)
    phases = {name: tm[i] / samples / 1e3 for i, name in ((L.T_IFACE, "interface"), (L.T_EARLY, "early_tasks"),
                                                          (L.T_POST, "post"), (L.T_LATE, "other_tasks"),
                                                          (L.T_COMPLETE, "complete"))}
    phases["checks"] = tm[L.T_CHECK] / steps / 1e3
    frames = writer.frames                  # frames recorded over the timed steps, one in TIME_EVERY of them timed
    phases["frames"] = tm[L.T_FRAMES] / max(tm[L.T_FRAME_SAMPLES], 1) * frames / steps / 1e3
    allphases = comm.gather(phases)
    rss = comm.gather(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024)
    events = comm.reduce(sim.counters - c0)
    owned = comm.gather(sim.state.n_owned)
    if rank == 0:
        import shutil
        shutil.rmtree(tmp, ignore_errors=True)
        print(json.dumps({
            "l": a.l, "mode": a.mode, "precision": a.precision, "ranks": size, "nodes": n_nodes,
            "owned_per_rank": owned, "steps": steps, "loop_s": wall, "us_per_step": wall / steps * 1e6,
            "node_updates_per_s": n_nodes * steps / wall,
            "phases_us_per_step": allphases, "exchange_us_per_step": max(p["post"] + p["complete"] for p in allphases),
            "frames_written": writer.frames, "frame_write_us": writer.seconds / max(writer.frames, 1) * 1e6,
            "events_written": writer.events, "event_write_us_per_step": writer.event_seconds / steps * 1e6,
            "startup_s": {"imports": T_IMPORTS, "derive": t_derive, "build": t_build, "first_call": t_first},
            "omega_method": st.omega_method, "breaks": int(events[0]), "reforms": int(events[1]),
            "peak_rss_bytes": rss, "bytes_per_node": max(rss) / max(owned)}), flush=True)


if __name__ == "__main__":
    main()
