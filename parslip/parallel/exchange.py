"""How halo copies are refreshed: the exchange the compiled loop calls, and its plan.

The compiled time loop calls the phases below and never MPI directly; the
plan it is passed says who the peers are, and its *type* chooses the code
numba compiles:

- ``NullPlan`` (one rank): every phase is a no-op.  The loop compiled for it
  references no MPI symbol, so a one-rank run never loads an MPI library.
- ``halo_mpi.Plan`` (several ranks): ``post`` packs the OWNED values each
  peer keeps as HALO and starts its persistent receives and sends (MPI_Startall),
  or, for a peer on the same node, packs them into its own shared window
  and sets a flag the peer reads (``parallel.shm``); ``complete`` waits (MPI_Waitall,
  or the peer's flag) and unpacks into the HALO copies; ``progress`` lets MPI move
  the messages while the loop computes (MPI_Testall); ``reduce_max`` takes
  the MAX of the loop's flags over all ranks (MPI_Allreduce).
  ``parallel.halo_mpi`` holds them and is imported only when a communicator
  with more than one rank is used.

What travels is given by ``parallel.layout``: row segments of positions, and
the travelling rows of the bond table (``model.interface.BONDS.travel``) of
the block's interface sites.
"""
from __future__ import annotations

import numpy as np
from numba import types
from numba.extending import overload

from .plans import SEGMENT, SITES, NullPlan, Plan  # noqa: F401 - the plan types the phases dispatch on


def build_plan(layout, dtype, comm=None, shared=True):
    """The exchange plan of ``layout``: a ``NullPlan`` without a communicator of more than one rank,
    else the MPI plan (this loads the MPI library mpi4py uses), through shared memory to the peers on this
    rank's node if ``shared`` (``run.exchange``)."""
    if comm is None or comm.Get_size() == 1:
        return NullPlan(1)
    from . import halo_mpi
    return halo_mpi.build_plan(layout, dtype, comm, shared)


def describe(plan, comm) -> str:
    """Collective: how halo copies travel, over all ranks, for the run's log: ``halo exchange: shared memory
    with A to B peers on its node, messages to C to D`` (the fewest and most on any rank), or ``halo exchange:
    MPI messages`` when no rank shares memory with a peer; empty on one rank."""
    if comm is None or comm.Get_size() == 1:
        return ""
    from mpi4py import MPI
    shared = int(plan.shared.sum())
    mine = np.array([shared, -shared, len(plan.peer) - shared, shared - len(plan.peer)], np.int64)
    got = np.empty_like(mine)
    comm.Allreduce(mine, got, op=MPI.MIN)
    lo_s, hi_s, lo_m, hi_m = (int(v) for v in (got[0], -got[1], got[2], -got[3]))
    if hi_s == 0:
        return "halo exchange: MPI messages"
    span = lambda lo, hi: f"{lo}" if lo == hi else f"{lo} to {hi}"      # noqa: E731
    line = f"halo exchange: shared memory with {span(lo_s, hi_s)} {'peers' if hi_s > 1 else 'peer'} on its node"
    return line + (f", messages to {span(lo_m, hi_m)}" if hi_m else "")


def release(plan) -> None:
    """Free what a plan holds in MPI (its persistent requests); nothing on one rank."""
    if not isinstance(plan, NullPlan):
        from .halo_mpi import release as free
        free(plan)


def _compiled_only(*args):
    raise TypeError("the exchange phases run in compiled code; from Python call parslip.parallel.halo_mpi's "
                    "mpi_post, mpi_complete, mpi_progress, mpi_reduce_max with an MPI plan")


def post(plan, bx, by, tx, ty, bonds):
    """Pack and send the OWNED values peers keep as HALO (positions, travelling bond rows); post the
    receives.  Returns the OR of MPI error codes (0 on one rank).  Compiled code only."""
    _compiled_only()


def complete(plan, bx, by, tx, ty, bonds):
    """Wait for the messages ``post`` started and unpack them into the HALO copies; returns the OR of MPI
    error codes (0 on one rank).  Compiled code only."""
    _compiled_only()


def progress(plan):
    """Let MPI move the posted messages while the loop computes; returns an MPI error code."""
    _compiled_only()


def reduce_max(plan, flags):
    """``flags`` (int64) becomes its element-wise MAX over all ranks; returns an MPI error code."""
    _compiled_only()


def _is_null(plan) -> bool:
    return isinstance(plan, types.BaseNamedTuple) and plan.instance_class is NullPlan


@overload(post, inline="always")
def _post(plan, bx, by, tx, ty, bonds):
    if _is_null(plan):
        return lambda plan, bx, by, tx, ty, bonds: 0
    from .halo_mpi import mpi_post       # typing the MPI plan: the MPI library is loaded by now
    return lambda plan, bx, by, tx, ty, bonds: mpi_post(plan, bx, by, tx, ty, bonds)


@overload(complete, inline="always")
def _complete(plan, bx, by, tx, ty, bonds):
    if _is_null(plan):
        return lambda plan, bx, by, tx, ty, bonds: 0
    from .halo_mpi import mpi_complete
    return lambda plan, bx, by, tx, ty, bonds: mpi_complete(plan, bx, by, tx, ty, bonds)


@overload(progress, inline="always")
def _progress(plan):
    if _is_null(plan):
        return lambda plan: 0
    from .halo_mpi import mpi_progress
    return lambda plan: mpi_progress(plan)


@overload(reduce_max, inline="always")
def _reduce_max(plan, flags):
    if _is_null(plan):
        return lambda plan, flags: 0
    from .halo_mpi import mpi_reduce_max
    return lambda plan, flags: mpi_reduce_max(plan, flags)
