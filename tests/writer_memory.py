"""Run under mpiexec by tests/test_writer_memory.py (not by pytest): what rank 0 allocates while the writer
writes one snapshot, one block of interface frames and one flush of bond events.

    mpiexec -n N python tests/writer_memory.py OUT.vtkhdf

Builds the run's state for a fixed lattice (nothing is stepped), hands the writer (``io.output.Output``)
drawn fields of every OWNED node and site and 20 drawn bond events per site, and measures with
tracemalloc (which sees NumPy's arrays and every pickled message) the peak of what rank 0 allocates
during each call, above what it held before.  Prints one JSON object from rank 0: each call's peak, and
the bytes of the fields rank 0 itself hands over.
"""
import inspect
import json
import sys
import tracemalloc

import numpy as np
from mpi4py import MPI

from parslip.engine.simulation import Simulation
from parslip.io.output import Output
from parslip.parallel import collective
from parslip.scene.derive import derive
from parslip.scene.load import load

SCENE = {"lattice.top_rows": 20, "lattice.top_cols": 300, "lattice.bottom_rows": 10, "lattice.bottom_cols": 400,
         "drive.duration": 1.0, "output.snapshots": 2, "load.ramp": 0.0, "load.settle": 0.0}
EVENTS_PER_SITE = 20


def peak(fn) -> int:
    """Bytes rank 0 allocated at the peak of ``fn()``, above what it held before; every rank calls it."""
    tracemalloc.reset_peak()
    before = tracemalloc.get_traced_memory()[0]
    fn()
    return tracemalloc.get_traced_memory()[1] - before


def main(path):
    comm = MPI.COMM_WORLD
    st = collective.decide(comm, lambda: derive(load({}, SCENE)))
    sim = Simulation(st, comm)
    out = Output(path, sim.output_spec(), comm)
    rng = np.random.default_rng(comm.Get_rank())
    n, sites = sim.state.n_owned, len(sim.state.owned_partner())
    pos, vel, sig = rng.random((n, 3)), rng.random((n, 3)), rng.random((n, 3))
    partner = sim.state.owned_partner()
    far = rng.random((sites, 3))
    fr = sim.frames
    count = fr.intact.shape[0]
    fr.step[:count] = st.n_drive_start + np.arange(count) * st.frame_every
    steps = np.repeat(np.arange(EVENTS_PER_SITE) * 7, sites)            # every rank's events at the same steps
    site = np.tile(np.arange(sites) + sim.state.site0(), EVENTS_PER_SITE)
    events = (steps, site, np.ones(len(steps), np.uint8), site, rng.random(len(steps)), rng.random(len(steps)))
    own_event_bytes = int(sum(np.asarray(e).nbytes for e in events))
    if "fields" in inspect.signature(out.interface_events).parameters:       # events by name (the contract's)
        events = (dict(zip(("step", "site", "kind", "partner", "energy", "traction"), events),
                       dissipated=np.zeros(len(steps))),)
    snap = (0, 0.0, pos, vel, sig, partner) + ((far,) if "far_pos" in inspect.signature(out.snapshot).parameters
                                              else ())
    try:                                # load the exact sums' compiled kernels first: not the writer's memory
        from parslip.parallel.exact_sum import Expansions
        (Expansions.of(np.ones((2, 2))) + Expansions.of(np.ones((2, 2)))).rounded(True)
    except ImportError:                 # a version without them
        pass
    tracemalloc.start()
    got = {"snapshot": peak(lambda: out.snapshot(*snap)),
           "frames": peak(lambda: out.interface_frames(0, count, fr, np.zeros(count), sim.budget_frames(count))),
           "events": peak(lambda: out.interface_events(0, *events, lambda k: k * 1.0)),
           "own_snapshot_bytes": int(pos.nbytes + vel.nbytes + sig.nbytes),
           "own_event_bytes": own_event_bytes,
           "ranks": comm.Get_size(), "nodes": st.lattice.n_nodes}
    tracemalloc.stop()
    out.close()
    if comm.Get_rank() == 0:
        print(json.dumps(got))


if __name__ == "__main__":
    main(sys.argv[1])
