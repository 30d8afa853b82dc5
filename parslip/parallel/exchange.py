"""How halo copies are refreshed: the exchange the compiled loop calls, and its plan.

The compiled time loop calls ``exchange(phase, plan, ...)`` and never MPI
directly; the plan it is passed says who the peers are, and its *type*
chooses the code numba compiles:

- ``NullPlan`` (one rank): every phase is a no-op.  The loop compiled for it
  references no MPI symbol, so a one-rank run never loads an MPI library.
- ``halo_mpi.Plan`` (several ranks): phase POST packs the OWNED values each
  peer keeps as HALO and posts MPI_Irecv and MPI_Isend; COMPLETE waits
  (MPI_Waitall) and unpacks into the HALO copies; PROGRESS lets MPI move the
  messages while the loop computes (MPI_Testall); REDUCE takes the MAX of the
  loop's flags over all ranks (MPI_Allreduce).  ``parallel.halo_mpi`` holds
  it and is imported only when a communicator with more than one rank is used.

What travels is given by ``parallel.layout``: row segments of positions, and
the bond state (partner, x0) of the block's interface sites.
"""
from __future__ import annotations

from collections import namedtuple

import numpy as np
from numba import types
from numba.extending import overload

# Phases of one exchange.
POST, COMPLETE, REDUCE, PROGRESS = 0, 1, 2, 3

# One rank: nothing to exchange.  (numba needs a field; ``ranks`` is always 1.)
NullPlan = namedtuple("NullPlan", "ranks")

# The MPI plan (built by ``halo_mpi.build_plan``).  Its class lives here, not in ``halo_mpi``: numba's
# cache index names the types of every compiled version of the loop, and reading that index must not
# import the module that loads MPI.  A row segment that travels (array row and columns, with the pad),
# and a run of interface sites:
SEGMENT = np.dtype([("block", np.int64), ("row", np.int64), ("j0", np.int64), ("n", np.int64)])
SITES = np.dtype([("j0", np.int64), ("n", np.int64)])
Plan = namedtuple("Plan", "peer ss ss_ptr sts sts_ptr rs rs_ptr rts rts_ptr sbuf sb_ptr rbuf rb_ptr "
                          "req status handles rflags")


def build_plan(layout, dtype, comm=None):
    """The exchange plan of ``layout``: a ``NullPlan`` without a communicator of more than one rank,
    else the MPI plan (this loads the MPI library mpi4py uses)."""
    if comm is None or comm.Get_size() == 1:
        return NullPlan(1)
    from . import halo_mpi
    return halo_mpi.build_plan(layout, dtype, comm)


def exchange(phase, plan, bx, by, tx, ty, partner, x0, flags):
    """One phase of the halo exchange of ``plan``; returns the OR of MPI error codes (0 on one rank).

    Compiled code only (the implementation is chosen by the plan's type, see the module docstring);
    from Python, call ``halo_mpi.mpi_exchange`` with an MPI plan.
    """
    raise TypeError("exchange() runs in compiled code; from Python call parslip.parallel.halo_mpi.mpi_exchange")


def _is_null(plan) -> bool:
    return isinstance(plan, types.BaseNamedTuple) and plan.instance_class is NullPlan


@overload(exchange, inline="always")
def _exchange(phase, plan, bx, by, tx, ty, partner, x0, flags):
    if _is_null(plan):
        def nothing(phase, plan, bx, by, tx, ty, partner, x0, flags):
            return 0
        return nothing
    from .halo_mpi import mpi_exchange       # typing the MPI plan: the MPI library is loaded by now

    def with_mpi(phase, plan, bx, by, tx, ty, partner, x0, flags):
        return mpi_exchange(phase, plan, bx, by, tx, ty, partner, x0, flags)
    return with_mpi
