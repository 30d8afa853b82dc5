"""Decisions every rank must share, made once: rank 0 decides, the others learn it.

Anything that leads into a collective or touches the filesystem (the scene read, the output planned,
a sweep's points dealt) is decided on rank 0 and broadcast, with a ``ConfigError`` carried to every
rank alike, so that no rank goes on alone or stops alone.  ``comm`` None (or of one rank) runs the
function here, with no MPI.
"""
from __future__ import annotations

from ..errors import ConfigError, RunError


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
