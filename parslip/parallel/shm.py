"""Halo messages between ranks on one node through memory they share (MPI-3 shared windows), not MPI calls.

Why: on one node an MPI message costs its calls, not its bytes.  Measured here (MPICH 5 ch4, 400 doubles
each way, persistent requests): MPI_Startall 0.9-2.2 us and MPI_Waitall 1.5-2.6 us a round even with the
message already there, 2.5-5 us of a 12 us step of the README's main job on 2 ranks.  Copying the same
values costs about 0.3 us.

How (``halo_mpi.build_plan`` makes the windows, ``halo_mpi.mpi_post`` / ``mpi_complete`` use them):

- Every rank of a node allocates, in one window over the node's communicator (``MPI_Win_allocate_shared``),
  its send buffer twice (one copy per step parity), and in a second window one flag per peer (a cache line
  each, so no two flags share a line).
- A sender packs each peer's message into its own window at the step's parity, then publishes the step's
  sequence number in that peer's flag with a release store.  The receiver waits until an acquire load of
  the flag reads the number, then unpacks straight from the sender's window.  Nothing else is called: no
  lock, no MPI, and a rank writes only its own memory.
- Two copies make it safe without a reply: a sender writes parity p of step n + 1 after it saw its peer's
  step n (the exchange is symmetric: every peer sends to every peer, an empty message included), which the
  peer published after it had unpacked step n - 1, the last one of parity p.
- The lines a sender writes were read last by its peer, so each has to leave the peer's cache first.  The
  sender asks for all of them at once before it packs (``prefetch_write``), so they travel together rather
  than one after the other as the stores reach them.  Measured on 2 ranks of the main job's scene (this
  host's two cores share a cache most of the time): posting took 0.70-0.77 us with it, 0.90-0.94 us
  without; in stretches where they did not, 2.4-2.6 us without it.

Where a peer shares no node, its messages stay MPI messages (persistent requests): a plan may mix both.

The flags are int64 in ordinary memory, read and written with LLVM atomics (``load_acquire``,
``store_release``; on x86-64 plain moves the compiler may not reorder).  A rank that waits spins a little,
then yields its core (``sched_yield``), then sleeps a few microseconds at a time, so oversubscribed ranks
(more ranks than cores) still let the peer they wait for run.
"""
from __future__ import annotations

import ctypes

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic

# The flags' stride (int64): one cache line per flag.
FLAG_STRIDE = 8
# Waiting: spin this many times, then yield the core this many more, then sleep SLEEP_US at a time.
SPINS, YIELDS, SLEEP_US = 2000, 20000, 20

_sched_yield = types.ExternalFunction("sched_yield", types.int32())
_usleep = types.ExternalFunction("usleep", types.int32(types.uint32))


@intrinsic
def load_acquire(typingctx, arr, idx):
    """arr[idx] (an int64 array) read with an acquire load: what the writer stored before its release store
    of this value is visible after it."""
    sig = types.int64(arr, idx)

    def codegen(context, builder, signature, args):
        aryty = signature.args[0]
        ary = context.make_array(aryty)(context, builder, args[0])
        ptr = cgutils.get_item_pointer(context, builder, aryty, ary, [args[1]], wraparound=False)
        return builder.load_atomic(ptr, "acquire", 8)
    return sig, codegen


@intrinsic
def store_release(typingctx, arr, idx, value):
    """arr[idx] = value (an int64 array) with a release store: every store before it is visible to a reader
    whose acquire load reads this value."""
    sig = types.void(arr, idx, value)

    def codegen(context, builder, signature, args):
        aryty = signature.args[0]
        ary = context.make_array(aryty)(context, builder, args[0])
        ptr = cgutils.get_item_pointer(context, builder, aryty, ary, [args[1]], wraparound=False)
        val = context.cast(builder, args[2], signature.args[2], types.int64)
        builder.store_atomic(val, ptr, "release", 8)
        return context.get_dummy_value()
    return sig, codegen


@intrinsic
def prefetch_write(typingctx, arr, idx):
    """Ask for the cache line of arr[idx] in a state to write it (x86 ``prefetchw``): a hint, which changes no
    value.  The line a peer read last has to leave that peer's cache before this core writes it; lines asked
    for together leave together."""
    sig = types.void(arr, idx)

    def codegen(context, builder, signature, args):
        aryty = signature.args[0]
        ary = context.make_array(aryty)(context, builder, args[0])
        ptr = cgutils.get_item_pointer(context, builder, aryty, ary, [args[1]], wraparound=False)
        i8p, i32 = ir.IntType(8).as_pointer(), ir.IntType(32)
        # The typed-pointer name (LLVM 14, numba 0.58-0.60); newer LLVMs rename it to llvm.prefetch.p0 as
        # they read it.
        fn = cgutils.get_or_insert_function(builder.module, ir.FunctionType(ir.VoidType(), [i8p, i32, i32, i32]),
                                            "llvm.prefetch.p0i8")
        builder.call(fn, [builder.bitcast(ptr, i8p), i32(1), i32(3), i32(1)])     # write, keep, data
        return context.get_dummy_value()
    return sig, codegen


@njit(cache=True, _nrt=False)
def wait_for(flags, i, value):
    """Return once flags[i] reads ``value`` or more (acquire): spin, then yield the core, then sleep."""
    spins = 0
    while load_acquire(flags, i) < value:
        spins += 1
        if spins > SPINS + YIELDS:
            _usleep(np.uint32(SLEEP_US))
        elif spins > SPINS:
            _sched_yield()


class Windows:
    """The two shared windows of one rank on its node: ``data`` (the send buffer's two parities, in the
    state's float type) and ``flags`` (int64, one cache line per peer), with views of every node rank's
    segment in this process's address space.  Collective over ``node`` (made and freed together)."""

    def __init__(self, node, dtype, values: int, npeer: int):
        from mpi4py import MPI
        self.node = node
        item = np.dtype(dtype).itemsize
        # At least a cache line each, so every rank's segment has an address of its own.
        self._data = MPI.Win.Allocate_shared(max(2 * values * item, 64), item, comm=node)
        self._flags = MPI.Win.Allocate_shared(max(npeer, 1) * FLAG_STRIDE * 8, 8, comm=node)
        self.data, self.data_base = _span(self._data, node.Get_size(), dtype)
        self.flags, self.flags_base = _span(self._flags, node.Get_size(), np.int64)
        me = node.Get_rank()
        self.data[self.data_base[me]:self.data_base[me] + 2 * values] = 0
        self.flags[self.flags_base[me]:self.flags_base[me] + max(npeer, 1) * FLAG_STRIDE] = 0
        node.Barrier()        # every flag reads 0 before any rank posts

    def free(self) -> None:
        """Free both windows (collective over the node)."""
        for w in (self._data, self._flags):
            w.Free()


def _span(win, size: int, dtype):
    """One array over every node rank's segment of ``win`` (as mapped in this process), and each rank's first
    index in it.  MPI allocates the segments contiguously unless told not to; the array spans from the lowest
    to the highest address either way, and only the segments themselves are ever read or written."""
    item = np.dtype(dtype).itemsize
    segs = []
    for r in range(size):
        buf, _ = win.Shared_query(r)
        segs.append((buf.address, len(buf)))
    lo = min(a for a, _ in segs)
    hi = max(a + n for a, n in segs)
    if any((a - lo) % item for a, _ in segs):
        raise RuntimeError("parslip: a shared window's segments are not aligned to its items")
    raw = (ctypes.c_char * (hi - lo)).from_address(lo)
    arr = np.frombuffer(raw, dtype=dtype, count=(hi - lo) // item)
    return arr, np.array([(a - lo) // item for a, _ in segs], np.int64)
