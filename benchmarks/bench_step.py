"""Throughput and memory of the time loop: prints numbers, asserts nothing.

    python benchmarks/bench_step.py [--scale 1 2 5] [--steps 3000]
    mpiexec -n 2 python benchmarks/bench_step.py --scale 5

For each scale s the paper's geometry is multiplied by s (l = 100 s), the
state is settled for a few steps to compile, then --steps steps are timed.
Reports node-updates/s per rank and per run, the time per step, and the peak
resident memory of rank 0.
"""
import argparse
import resource
import time

from parslip.scene.load import resolve
from parslip.parallel.decomposition import SlabExchanger
from parslip.engine.simulation import Simulation
from parslip.scene.derive import derive


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--scale", type=int, nargs="+", default=[1, 2, 5])
    p.add_argument("--steps", type=int, default=3000)
    a = p.parse_args()
    from mpi4py import MPI
    comm = MPI.COMM_WORLD
    size = comm.Get_size()
    for s in a.scale:
        scene = resolve({}, [("lattice.top_rows", 10 * s), ("lattice.top_cols", 100 * s),
                             ("lattice.bottom_rows", 20 * s), ("lattice.bottom_cols", 300 * s),
                             ("output.snapshots", 0)])
        st = derive(scene, comm.bcast((lambda d: (d.omega_max, d.omega_method))(derive(scene))
                                      if comm.rank == 0 else None))
        sim = Simulation(st, SlabExchanger(comm) if size > 1 else None, comm)
        sim.run(until=20)                      # compile and warm up
        comm.Barrier()
        t0 = time.perf_counter()
        sim.run(until=20 + a.steps)
        comm.Barrier()
        wall = time.perf_counter() - t0
        n = st.lattice.n_nodes
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        if comm.rank == 0:
            ups = a.steps * n / wall
            print(f"l = {100 * s:5d}  nodes = {n:8d}  ranks = {size}  {wall / a.steps * 1e6:8.1f} us/step  "
                  f"{ups / 1e6:7.1f} M node-updates/s  ({ups / size / 1e6:6.1f} M per rank)  "
                  f"peak RSS rank 0 = {rss:6.0f} MiB", flush=True)


if __name__ == "__main__":
    main()
