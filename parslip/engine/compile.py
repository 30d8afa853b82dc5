"""The compiled kernels' first call, once per job: one rank per kernel cache compiles, the others load.

numba compiles the time loop (``loop.advance`` and every kernel it calls) on its first call and keeps the
machine code in its cache, ``io.cache.kernel_cache_dir``.  Left to themselves, the ranks of a job on a cold
cache would all compile the same loop at once: N ranks, N compiles, into one folder when it is shared.
Here, on several ranks:

1. the compiling ranks are chosen (``_compilers``): rank 0, for every rank that sees rank 0's cache folder
   (a file rank 0 makes in it is there), and on each node the lowest rank that does not (a folder on the
   node's own disk), so each folder is filled once; and a helper, the lowest other rank that sees rank 0's
   folder;
2. they make the first call, which compiles the kernels into their folder, while the others sleep
   (``parallel.collective.wait_quietly``: MPICH's blocking calls poll a core); meanwhile the helper compiles
   ``side`` into the same folder: the frames' kernels, which the loop's compile reaches last and then loads,
   and the kernels the loop does not call (the output's exact sums, the snapshots' stresses).  The first
   run's wall time is shortened by their compile, its CPU time not lengthened;
3. their outcome is told to every rank (``parallel.collective.outcome``): a compile that failed ends every
   rank with the same RunError, none left waiting; otherwise every rank makes the calls it has not made,
   which load the kernels from the cache.

Why a rank never reads a half-written or a stale entry: numba writes each index and data file under a
temporary name and renames it, so a reader sees the whole file or none; a rank reads the cache only after
the rank that filled it has returned; and the folder is named by a hash of the kernels' sources, so no
entry of another version of them is found.  A rank whose lookup still misses (numba keys an entry by the
CPU model too: a node of another kind on a mixed cluster) compiles for itself: the same results, and the
log line counts it.

Which ranks compiled, and how many functions, is read from numba's own compile events ("numba:compile"),
not guessed from the time taken; the log line states the wall time and the CPU time the first call took.
"""
from __future__ import annotations

import contextlib
import os
import tempfile
import time
from dataclasses import dataclass

import numpy as np

from .. import hooks
from ..io.cache import kernel_cache_dir
from ..parallel.collective import Attempt, outcome


@dataclass(frozen=True)
class FirstCall:
    """How the kernels' first call went: ``ranks`` in the job, ``compiled_on`` of them compiled something,
    ``functions`` compiled (summed over the ranks), in ``seconds`` of wall time (rank 0's, the waits
    included) and ``cpu_s`` of CPU time (summed over the ranks)."""
    ranks: int
    compiled_on: int
    functions: int
    seconds: float
    cpu_s: float

    def line(self) -> str | None:
        """The log line of a job in which some rank compiled (None when every rank loaded the kernels)."""
        if not self.compiled_on:
            return None
        took = f"compiled the time loop in {self.seconds:.0f} s ({self.cpu_s:.0f} s of CPU"
        if self.ranks == 1:
            return f"{took}; stored in numba's cache for later runs)"
        rest = ", the others loaded it from numba's cache" if self.compiled_on < self.ranks else " sharing the work"
        return (f"{took} summed over the ranks; {self.functions} functions): on {self.compiled_on} of "
                f"{self.ranks} ranks{rest}")


def compiled_names(fn) -> list[str]:
    """Run ``fn``; the functions numba compiled meanwhile (a cache load is not a compile), less the
    implementations of overloads, which numba compiles in every process while it types a caller and
    never caches (``<locals>`` in their names: ``kernels.floats.like``'s, say)."""
    from numba.core import event
    with event.install_recorder("numba:compile") as rec:
        fn()
    names = [f"{e.data['dispatcher'].py_func.__module__}.{e.data['dispatcher'].py_func.__qualname__}"
             for _, e in rec.buffer if e.is_start]
    return [name for name in names if "<locals>" not in name]


def _mark(folder: str) -> str | None:
    """A new empty file in ``folder`` (made if need be), or None if it cannot be written."""
    try:
        os.makedirs(folder, exist_ok=True)
        fd, path = tempfile.mkstemp(dir=folder, prefix=".first-call-")
        os.close(fd)
        return path
    except OSError:
        return None


def _compilers(comm) -> tuple[bool, bool, str | None]:
    """Whether this rank compiles the loop, whether it is the helper that compiles the rest meanwhile, and the
    file rank 0 made in its cache folder (to remove once every rank has looked; None elsewhere).  Collective:
    a broadcast, a reduction within each node, then one over the job.

    A rank that sees the file shares rank 0's folder (one folder on a shared filesystem serves the whole
    job); among those that do not, the lowest of each node compiles for the node.  The helper is the lowest
    rank but 0 that sees it.  If rank 0 cannot write its folder, numba cannot cache in it either: every rank
    compiles for itself, with no helper."""
    from mpi4py import MPI
    rank, size = comm.Get_rank(), comm.Get_size()
    folder = kernel_cache_dir()
    marker = _mark(folder) if rank == 0 else None
    name = comm.bcast(os.path.basename(marker) if marker else None, root=0)
    if name is None:
        return True, False, None
    sees = rank == 0 or os.path.exists(os.path.join(folder, name))
    node = comm.Split_type(MPI.COMM_TYPE_SHARED, key=rank)
    try:
        first = node.allreduce(size if sees else rank, op=MPI.MIN)
    finally:
        node.Free()
    helper = comm.allreduce(rank if sees and rank != 0 else size, op=MPI.MIN)
    return rank == 0 or (not sees and rank == first), rank == helper, marker


def first_call(comm, call, side=None) -> FirstCall:
    """``call`` (the kernels' first call: it compiles them or loads them from the cache) and ``side`` (kernels
    called outside the loop, or None) on every rank of ``comm`` (None: this process alone), each compiled
    once per cache folder (the module's steps).  Collective: if either fails on any rank, every rank raises
    the same RunError.  The ``compile_error`` test hook makes the first of them this rank makes fail on the
    rank it names (a compiling rank, the helper, or a loading one)."""
    t0, c0 = time.monotonic(), time.process_time()
    rank = comm.Get_rank() if comm is not None else 0
    calls = [f for f in (call, side) if f is not None]

    def first(fns):
        def run():
            if hooks.get("compile_error") == rank:
                raise RuntimeError(f"injected failure of the compile on rank {rank} (test hook compile_error)")
            return then(fns)
        return run

    def then(fns):
        return [name for fn in fns for name in compiled_names(fn)]
    if comm is None or comm.Get_size() == 1:
        names = first(calls)()
        return FirstCall(1, int(bool(names)), len(names), time.monotonic() - t0, time.process_time() - c0)
    from mpi4py import MPI
    compiles, helps, marker = _compilers(comm)
    early = [call] if compiles else ([side] if helps and side is not None else [])
    mine = Attempt(first(early)) if early else None
    try:
        outcome(comm, mine)                 # the others sleep here while the compiling ranks work
    finally:
        if marker is not None:
            with contextlib.suppress(OSError):
                os.unlink(marker)
    names = mine.value if mine is not None else []
    late = [f for f in calls if not any(f is g for g in early)]
    mine = Attempt(first(late) if mine is None else lambda: then(late))
    outcome(comm, mine)
    names = names + mine.value
    sums = np.array([bool(names), len(names), time.process_time() - c0], dtype=float)
    comm.Allreduce(MPI.IN_PLACE, sums, op=MPI.SUM)
    return FirstCall(comm.Get_size(), int(sums[0]), int(sums[1]), time.monotonic() - t0, float(sums[2]))
