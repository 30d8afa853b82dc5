"""The exchange plans' types, apart from the code that builds or runs them.

``exchange`` dispatches on them and ``halo_mpi`` builds the MPI one; both import this module, which
loads no MPI: numba's cache index names the types of every compiled version of the loop, and reading
that index must not import the module that loads MPI.
"""
from __future__ import annotations

from collections import namedtuple

import numpy as np

# One rank: nothing to exchange.  (numba needs a field; ``ranks`` is always 1.)
NullPlan = namedtuple("NullPlan", "ranks")

# The MPI plan (built by ``halo_mpi.build_plan``).  A rectangle of row segments that travels (the first array
# row and how many consecutive rows, and the columns, with the pad: a bulk halo of one column over every row
# of a block is one rectangle, not a segment per row), and a run of interface sites:
SEGMENT = np.dtype([("block", np.int64), ("row", np.int64), ("rows", np.int64), ("j0", np.int64), ("n", np.int64)])
SITES = np.dtype([("j0", np.int64), ("n", np.int64)])
# ``travel``: the indices of the bond table's rows that travel (``model.interface.BONDS.travel``); ``rflags``:
# the reduction's receive buffer (and MPI_Testall's flag), REDUCE_WORDS int64: the loop's flags must fit.
REDUCE_WORDS = 32
# A peer on this rank's node is reached through shared windows (``parallel.shm``), the others by MPI messages
# (``req``: persistent requests for those only, receives then sends).  ``shared[i]``: 1 if peer i shares the
# node; ``node``: the data window's array over the node; ``dst[p, i]`` where in it (in this rank's own
# segment) this rank writes its message to peer i at step parity p, ``src[p, i]`` where peer i's message to
# it lies (in peer i's segment); ``ready``: the flag window's
# array, ``fdst[i]`` the flag this rank sets for peer i, ``fsrc[i]`` the one peer i sets for it; ``seq[0]``:
# the sequence number of the last step posted.
Plan = namedtuple("Plan", "peer ss ss_ptr sts sts_ptr rs rs_ptr rts rts_ptr sbuf sb_ptr rbuf rb_ptr "
                          "req status handles rflags travel shared node dst src ready fdst fsrc seq")
