"""The halo exchange's packing, timed apart from MPI: ns per value packed and unpacked; and, under mpiexec,
the whole exchange of a step as the loop makes it.

    python -m parslip.studies.bench.pack run/push_l1000.toml --ranks 64 --rank 20
    mpiexec -n 2 python -m parslip.studies.bench.pack run/push.toml --exchange

For one rank of a decomposition (its layout and exchange plan, ``parallel.halo_mpi``), arrays of the
state's shape are packed into the send buffer and unpacked from the receive buffer as ``mpi_post`` and
``mpi_complete`` do, many times over; the time of a pack and an unpack of every peer's message over the
values each carries is the cost per value the scaling model's ``b`` stands for (``studies.bench.scaling``),
measured directly rather than fitted.  No message is sent: MPI's own copy is left out.
"""
from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np
from numba import njit

from ...model.interface import BONDS
from ...parallel.halo_mpi import mpi_complete, mpi_post


def measure(setup, ranks: int, rank: int, seconds: float = 1.0) -> dict:
    """ns per value of packing and of unpacking rank ``rank``'s messages (median of repeats)."""
    from ...parallel.halo_mpi import build_plan, pack_all
    from ...parallel.layout import build_layout
    lay = build_layout(setup.lattice, rank, ranks, setup.reach, setup.drive.mode, overlap=setup.overlap)
    plan = build_plan(lay, np.float64)
    bl, tl = lay.blocks
    rng = np.random.default_rng(0)
    bx, by = rng.standard_normal(bl.shape), rng.standard_normal(bl.shape)
    tx, ty = rng.standard_normal(tl.shape), rng.standard_normal(tl.shape)
    bonds = rng.standard_normal((len(BONDS.names), tl.width))
    sent, received = int(plan.sbuf.shape[0]), int(plan.rbuf.shape[0])
    out = {"ranks": ranks, "rank": rank, "peers": int(plan.peer.shape[0]), "values_sent": sent,
           "values_received": received}
    for name, direction, values in (("pack", True, sent), ("unpack", False, received)):
        pack_all(plan, bx, by, tx, ty, bonds, direction, 1)         # compile, warm the caches
        reps = max(1, int(1e5 / max(values, 1)))
        times = []
        t_end = time.perf_counter() + seconds
        while time.perf_counter() < t_end or len(times) < 5:
            t0 = time.perf_counter_ns()
            pack_all(plan, bx, by, tx, ty, bonds, direction, reps)
            times.append((time.perf_counter_ns() - t0) / reps)
        out[f"{name}_ns_per_value"] = float(np.median(times)) / max(values, 1)
    out["ns_per_value"] = (out["pack_ns_per_value"] * sent + out["unpack_ns_per_value"] * received) / max(
        sent + received, 1)
    return out


@njit(cache=True)
def _exchanges(plan, bx, by, tx, ty, bonds, repeats):
    """``repeats`` exchanges as a step makes them (post, complete), in compiled code; returns the MPI errors."""
    err = 0
    for _ in range(repeats):
        err |= mpi_post(plan, bx, by, tx, ty, bonds)
        err |= mpi_complete(plan, bx, by, tx, ty, bonds)
    return err


def exchange(setup, comm, seconds: float = 1.0) -> dict:
    """Collective: us per exchange of a step on this communicator, each rank its own slab of ``setup``
    (pack, MPI's start, wait and copy, unpack, and waiting for the slowest peer), median of repeats, and
    what is left of it once the packing measured apart is taken away: the machine's MPI cost per message."""
    from ...parallel.exchange import build_plan as plan_of, release
    from ...parallel.layout import build_layout
    rank, size = comm.Get_rank(), comm.Get_size()
    lay = build_layout(setup.lattice, rank, size, setup.reach, setup.drive.mode, overlap=setup.overlap)
    plan = plan_of(lay, np.float64, comm, setup.shared_memory)
    bl, tl = lay.blocks
    bx, by, tx, ty = (np.zeros(b.shape) for b in (bl, bl, tl, tl))
    bonds = np.zeros((len(BONDS.names), tl.width))
    _exchanges(plan, bx, by, tx, ty, bonds, 10)
    reps, times = 200, []
    t_end = time.perf_counter() + seconds
    while True:
        comm.Barrier()
        t0 = time.perf_counter_ns()
        _exchanges(plan, bx, by, tx, ty, bonds, reps)
        times.append((time.perf_counter_ns() - t0) / reps / 1e3)
        if comm.allreduce(time.perf_counter() > t_end and len(times) >= 5, op=_mpi_lor()):
            break
    release(plan)
    packed = measure(setup, size, rank, min(seconds, 0.5))
    us = float(np.median(times))
    pack_us = packed["ns_per_value"] * (packed["values_sent"] + packed["values_received"]) / 1e3
    msgs = 2 * packed["peers"]
    return {"ranks": size, "rank": rank, "us_per_exchange": us, "pack_us": pack_us, "messages": msgs,
            "us_per_message": (us - pack_us) / max(msgs, 1)}


def _mpi_lor():
    from mpi4py import MPI
    return MPI.LOR


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m parslip.studies.bench.pack", description=__doc__.split("\n\n")[0])
    p.add_argument("scene", help="scene file, or a contact length l for the paper's geometry scaled (bench.case)")
    p.add_argument("--mode", default="shear", help="drive mode when SCENE is a contact length")
    p.add_argument("--ranks", type=int, default=2)
    p.add_argument("--rank", type=int, default=None, help="which rank (default: the middle one)")
    p.add_argument("--seconds", type=float, default=1.0)
    p.add_argument("--set", action="append", default=[])
    p.add_argument("--exchange", action="store_true", help="under mpiexec: time the whole exchange of a step")
    a = p.parse_args(argv)
    from ...scene.derive import derive
    from ...scene.load import load, overrides
    if a.scene.isdigit():
        from .case import scene_at
        st = derive(scene_at(int(a.scene), a.mode, "float64", overrides(a.set)))   # values as TOML literals
    else:
        st = derive(load(a.scene, a.set))
    if a.exchange:
        from mpi4py import MPI
        res = MPI.COMM_WORLD.gather(exchange(st, MPI.COMM_WORLD, a.seconds))
        if MPI.COMM_WORLD.Get_rank() == 0:
            print(json.dumps({"ranks": res}))
        return 0
    print(json.dumps(measure(st, a.ranks, a.ranks // 2 if a.rank is None else a.rank, a.seconds)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
