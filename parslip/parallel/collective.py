"""Decisions every rank must share, made once: rank 0 decides, the others learn it.

Anything that leads into a collective or touches the filesystem (the scene read, the output planned,
a sweep's points dealt) is decided on rank 0 and broadcast, with a ``ConfigError`` carried to every
rank alike, so that no rank goes on alone or stops alone.  Work whose result the others can reuse (the
compiled time loop, which they then load from numba's cache) is done on one rank first while they sleep
(``wait_quietly``), its failure told to every rank (``outcome``).  ``comm`` None (or of one rank) runs the
function here, with no MPI.
"""
from __future__ import annotations

import time

from ..errors import ConfigError, RunError

# s between two tests of a quiet wait (``wait_quietly``): the latency it adds, against a test's cost
# (microseconds) twenty times a second.
QUIET_POLL_S = 0.05


def decide(comm, fn):
    """Run ``fn`` on rank 0 and broadcast its value, or its error, to every rank of ``comm``.

    A ConfigError reaches every rank as that ConfigError; any other exception is raised as it is on rank 0
    and as a RunError naming it on the others, so that no rank is left waiting in the broadcast."""
    if comm is None or comm.Get_size() == 1:
        return fn()
    res, raised = None, None
    if comm.Get_rank() == 0:
        try:
            res = ("ok", fn())
        except ConfigError as e:
            res = ("err", str(e))
        except Exception as e:              # noqa: BLE001  (told to every rank, then raised here as it is)
            res, raised = ("fail", f"rank 0 failed: {type(e).__name__}: {e}"), e
    res = comm.bcast(res, root=0)
    if raised is not None:
        raise raised
    if res[0] == "err":
        raise ConfigError(res[1])
    if res[0] == "fail":
        raise RunError(res[1])
    return res[1]


def agree(comm, fn) -> None:
    """Run ``fn`` on every rank; if it raised ConfigError on any, raise the lowest such rank's on all."""
    try:
        fn()
        mine = None
    except ConfigError as e:
        mine = str(e)
    errors = [mine] if comm is None or comm.Get_size() == 1 else comm.allgather(mine)
    for e in errors:
        if e is not None:
            raise ConfigError(e)


def wait_quietly(comm, poll_s: float = QUIET_POLL_S) -> None:
    """A barrier that sleeps while it waits: MPI_Ibarrier, tested every ``poll_s`` seconds.

    MPICH's MPI_Barrier, like its other blocking calls, polls in a busy loop: a rank that waits a minute
    in it burns a minute of a core (on a shared node, the core another rank or job needs).  This one
    returns at most ``poll_s`` after the last rank arrived and costs almost nothing meanwhile."""
    if comm is None or comm.Get_size() == 1:
        return
    req = comm.Ibarrier()
    while not req.Test():
        time.sleep(poll_s)



class Attempt:
    """``fn`` run on this rank: its value, or its error as one line (``error``) and the exception itself."""

    def __init__(self, fn):
        self.value = self.error = self.raised = None
        try:
            self.value = fn()
        except Exception as e:              # noqa: BLE001  (told to every rank by ``outcome``, raised alike)
            self.error, self.raised = f"{type(e).__name__}: {e}", e


def outcome(comm, mine: Attempt | None) -> None:
    """Once every rank of ``comm`` is here (waited for quietly), the same RunError on every rank if any rank's
    ``mine`` failed, naming the lowest such rank and its error; None: nothing was attempted on this rank.

    A reduction and a broadcast from the failed rank: no rank gathers the others' results, and a rank that
    failed never leaves the others waiting in a collective it will not reach."""
    if comm is None or comm.Get_size() == 1:
        if mine is not None and mine.error is not None:
            raise RunError(f"rank 0 failed: {mine.error}") from mine.raised
        return
    from mpi4py import MPI
    wait_quietly(comm)
    rank, size = comm.Get_rank(), comm.Get_size()
    failed = comm.allreduce(rank if mine is not None and mine.error is not None else size, op=MPI.MIN)
    if failed == size:
        return
    error = comm.bcast(mine.error if rank == failed else None, root=failed)
    raise RunError(f"rank {failed} failed: {error}") from (mine.raised if mine is not None else None)
