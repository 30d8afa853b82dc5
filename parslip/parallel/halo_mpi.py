"""The MPI halo exchange: the plan of who sends what to whom, and the compiled calls that move it.

Imported only for a communicator of more than one rank (``exchange.build_plan``):
importing it loads the MPI library mpi4py uses (``parallel.mpi``).

``mpi_post`` packs the OWNED values each peer keeps as HALO and starts every receive and send at once
(persistent requests, made once per plan: MPI_Recv_init, MPI_Send_init; one MPI_Startall);
``mpi_complete`` waits (MPI_Waitall) and unpacks into the HALO copies.  A peer on the same node is reached
through shared memory instead (``parallel.shm``, unless the scene says ``run.exchange = "messages"``): the
message is packed into this rank's own shared window, a flag says it is there, and the peer unpacks it from
there, with no MPI call.
``mpi_progress`` tests the requests so MPI moves large messages while the loop computes; ``mpi_reduce_max``
takes the MAX of the loop's flags over all ranks (MPI_Allreduce).  One message per peer per step carries
every rectangle of row segments' x then y, then, for each run of interface sites, the travelling rows of
the bond table (``model.interface.BONDS.travel``, ``Plan.travel``) one after the other.  The bond
table is in the state's float type: integers (partners) are exact below
2^24 even in float32.
"""
from __future__ import annotations

import atexit

import numpy as np
from numba import njit

from ..model.interface import BONDS
from ..model.lattice import BOTTOM
from . import mpi, shm
from .plans import REDUCE_WORDS, SEGMENT, SITES, Plan

TAG = 7
TAG_LINK = 8          # set-up: where each peer's message lies in its sender's window


def build_plan(layout, dtype, comm=None, shared=True) -> Plan:
    """Index arrays and buffers of ``layout``'s exchange, in local columns; MPI handles from ``comm``
    (without one, a plan to inspect, e.g. its buffer sizes, not to run).  With ``shared``, peers on this
    rank's node are reached through shared windows (collective over ``comm``: every rank builds its plan
    at the same time, with the same ``shared``)."""
    from ..model.lattice import TOP

    blocks = layout.blocks
    peers = layout.peers

    def segs(lists, with_block):
        rows, ptr = [], [0]
        for lst in lists:
            start = len(rows)
            for sg in lst:
                if with_block:
                    b = blocks[sg.block]
                    new = [sg.block, b.prow(sg.row), 1, b.j(sg.lo), sg.hi - sg.lo]
                    last = rows[-1] if len(rows) > start else None
                    # The next row of the same block over the same columns: the rectangle grows by a row.
                    if last and last[0] == new[0] and last[1] + last[2] == new[1] and last[3:] == new[3:]:
                        last[2] += 1
                    else:
                        rows.append(new)
                else:
                    rows.append((blocks[TOP].j(sg[0]), sg[1] - sg[0]))
            ptr.append(len(rows))
        return np.array([tuple(r) for r in rows], SEGMENT if with_block else SITES), np.array(ptr, np.int64)

    ss, ss_ptr = segs([p.send for p in peers], True)
    rs, rs_ptr = segs([p.recv for p in peers], True)
    sts, sts_ptr = segs([p.send_sites for p in peers], False)
    rts, rts_ptr = segs([p.recv_sites for p in peers], False)

    def sizes(seg, ptr, sseg, sptr):
        out = [0]
        for i in range(len(peers)):
            sites = int(sseg["n"][sptr[i]:sptr[i + 1]].sum())
            n = 2 * int((seg["n"] * seg["rows"])[ptr[i]:ptr[i + 1]].sum()) + len(BONDS.travel) * sites
            out.append(out[-1] + n)
        return np.array(out, np.int64)

    sb_ptr = sizes(ss, ss_ptr, sts, sts_ptr)
    rb_ptr = sizes(rs, rs_ptr, rts, rts_ptr)
    h = mpi.handles(comm, dtype) if comm is not None else np.zeros(4, mpi.HANDLE_DTYPE)
    sbuf, rbuf = np.zeros(sb_ptr[-1], dtype), np.zeros(rb_ptr[-1], dtype)
    ranks = [p.rank for p in peers]
    link = _link(comm, ranks, sb_ptr, rb_ptr, dtype) if comm is not None and shared else _unlinked(ranks, dtype)
    by_mpi = [i for i in range(len(peers)) if not link["shared"][i]]
    req, made = _persistent(comm, ranks, by_mpi, sbuf, sb_ptr, rbuf, rb_ptr, dtype)
    status = np.zeros(max(1, 2 * len(peers)) * mpi.STATUS_BYTES, np.uint8)
    windows = link.pop("windows")
    plan = Plan(peer=np.array(ranks, np.int32), ss=ss, ss_ptr=ss_ptr, sts=sts, sts_ptr=sts_ptr,
                rs=rs, rs_ptr=rs_ptr, rts=rts, rts_ptr=rts_ptr, sbuf=sbuf, sb_ptr=sb_ptr,
                rbuf=rbuf, rb_ptr=rb_ptr, req=req, status=status, handles=h,
                rflags=np.zeros(REDUCE_WORDS, np.int64), travel=np.array(BONDS.travel, np.int64),
                seq=np.zeros(1, np.int64), **link)
    if made or windows is not None:
        _HELD[id(plan.seq)] = (made, windows, plan.seq)       # the key's array kept alive with its entry
    return plan


_NODES: dict = {}


def node_comm(comm):
    """The ranks of ``comm`` that share this rank's node (``MPI_Comm_split_type``, made once per communicator
    and kept: a collective on first use).  ``PARSLIP_NODE_RANKS=k`` splits each node further into groups of k
    consecutive ranks, as if a node held k ranks: the mixed transport (windows within a group, messages
    between groups) tested on one machine."""
    import os
    from mpi4py import MPI
    key = comm.py2f()
    if key not in _NODES:
        node = comm.Split_type(MPI.COMM_TYPE_SHARED, key=comm.Get_rank())
        group = int(os.environ.get("PARSLIP_NODE_RANKS", "0") or 0)
        if group > 0:
            whole, node = node, node.Split(color=node.Get_rank() // group, key=node.Get_rank())
            whole.Free()
        _NODES[key] = node
    return _NODES[key]


def _node_ranks(comm, node, ranks) -> list:
    """The ranks of ``node`` that ``ranks`` (of ``comm``) have; MPI.UNDEFINED for those on other nodes."""
    if not ranks:
        return []
    from mpi4py import MPI
    a, b = comm.Get_group(), node.Get_group()
    try:
        return MPI.Group.Translate_ranks(a, ranks, b)
    finally:
        a.Free()
        b.Free()


def _unlinked(ranks, dtype) -> dict:
    """The plan's shared-window fields when every peer gets messages (or the plan is only inspected)."""
    n = len(ranks)
    return dict(shared=np.zeros(n, np.uint8), node=np.zeros(0, dtype), dst=np.zeros((2, n), np.int64),
                src=np.zeros((2, n), np.int64), ready=np.zeros(0, np.int64), fdst=np.zeros(n, np.int64),
                fsrc=np.zeros(n, np.int64), windows=None)


def _link(comm, ranks, sb_ptr, rb_ptr, dtype) -> dict:
    """The shared windows of this rank's node and where, in them, each on-node peer's messages lie; every
    rank of ``comm`` calls it at once.  Each rank tells each peer where its message to that peer lies in its
    own segment (both parities), its length and the flag it sets for it; the receiver checks the length
    against what it unpacks."""
    from mpi4py import MPI
    node = node_comm(comm)
    n, tot = len(ranks), int(sb_ptr[-1])
    win = shm.Windows(node, dtype, tot, n)
    on = _node_ranks(comm, node, ranks)
    tell = np.array([[sb_ptr[i], tot + sb_ptr[i], sb_ptr[i + 1] - sb_ptr[i], i * shm.FLAG_STRIDE]
                     for i in range(n)], np.int64).reshape(n, 4)
    got = np.zeros_like(tell)
    reqs = [comm.Irecv(got[i], source=r, tag=TAG_LINK) for i, r in enumerate(ranks)]
    reqs += [comm.Isend(tell[i], dest=r, tag=TAG_LINK) for i, r in enumerate(ranks)]
    MPI.Request.Waitall(reqs)
    out = _unlinked(ranks, dtype)
    out.update(node=win.data, ready=win.flags, windows=win)
    me = node.Get_rank()
    for i, q in enumerate(on):
        if q == MPI.UNDEFINED:
            continue
        if got[i, 2] != rb_ptr[i + 1] - rb_ptr[i]:
            raise RuntimeError(f"parslip: rank {comm.Get_rank()} expects {rb_ptr[i + 1] - rb_ptr[i]} values "
                               f"from rank {ranks[i]}, which would send {got[i, 2]}")
        out["shared"][i] = 1
        out["dst"][:, i] = win.data_base[me] + tell[i, :2]
        out["src"][:, i] = win.data_base[q] + got[i, :2]
        out["fdst"][i] = win.flags_base[me] + tell[i, 3]
        out["fsrc"][i] = win.flags_base[q] + got[i, 3]
    return out


# What each plan holds in MPI (by the id of its ``seq`` array): its persistent requests (mpi4py's Prequest
# objects: made once, started every step from compiled code) and its shared windows; freed with ``release``.
_HELD: dict = {}


def _persistent(comm, ranks, which, sbuf, sb_ptr, rbuf, rb_ptr, dtype):
    """The requests of the peers ``which`` (indices into ``ranks``), [receive from each, send to each], as
    persistent requests over the plan's buffers (``MPI_Recv_init``, ``MPI_Send_init``): a step starts them
    and waits for them, with no request made or matched anew; and the mpi4py objects.  Zeros without a
    communicator (a plan to inspect)."""
    if comm is None or not which:
        return np.zeros(2 * len(which), mpi.REQUEST_DTYPE), []
    from mpi4py import MPI
    ftype = MPI.DOUBLE if np.dtype(dtype) == np.float64 else MPI.FLOAT
    made = [comm.Recv_init([rbuf[rb_ptr[i]:rb_ptr[i + 1]], ftype], source=ranks[i], tag=TAG) for i in which]
    made += [comm.Send_init([sbuf[sb_ptr[i]:sb_ptr[i + 1]], ftype], dest=ranks[i], tag=TAG) for i in which]
    # MPICH's int handles come as unsigned numbers (as the communicator's in ``mpi.handles``): wrap them.
    req = np.array([MPI._handleof(r) % (1 << 64) for r in made], np.uint64).astype(mpi.REQUEST_DTYPE)
    return req, made


def release(plan) -> None:
    """Free the plan's persistent requests (none may be active: after ``mpi_complete``) and its shared
    windows (collective over the node: every rank releases its plan at the same time)."""
    held = _HELD.pop(id(plan.seq), None)
    if held is not None:
        for r in held[0]:
            r.Free()
        if held[1] is not None:
            held[1].free()


@atexit.register
def _release_all() -> None:
    """Free the requests of the plans still held when the process ends, before mpi4py finalizes MPI (its exit
    handler was registered first, so it runs after this one): MPI_Finalize would report each as leaked.
    Their shared windows are left to MPI_Finalize: freeing a window is collective over the node, and a rank
    that leaves early (an error, a test's own plan) would leave the others waiting in it."""
    from mpi4py import MPI
    if MPI.Is_finalized():
        return
    for made, _, _ in list(_HELD.values()):
        for r in made:
            r.Free()
    _HELD.clear()


@njit(cache=True, _nrt=False, forceinline=True)
def _rect(buf, k, a, r0, rows, j0, n, out):
    """Rows r0 .. r0 + rows - 1 of ``a``, n values each from column j0, into ``buf`` at k (``out``) one row
    after the other, or back; returns k + rows n.  A column (n = 1, every bulk halo) is one strided loop."""
    if n == 1:
        if out:
            for r in range(rows):
                buf[k + r] = a[r0 + r, j0]
        else:
            for r in range(rows):
                a[r0 + r, j0] = buf[k + r]
        return k + rows
    if out:
        for r in range(r0, r0 + rows):
            for j in range(n):
                buf[k + j] = a[r, j0 + j]
            k += n
    else:
        for r in range(r0, r0 + rows):
            for j in range(n):
                a[r, j0 + j] = buf[k + j]
            k += n
    return k


@njit(cache=True, _nrt=False, forceinline=True)
def _move(buf, k, a, r, j0, n, out):
    """n values of row r of ``a`` from column j0 into ``buf`` at k (``out``), or back; returns k + n."""
    if out:
        for j in range(n):
            buf[k + j] = a[r, j0 + j]
    else:
        for j in range(n):
            a[r, j0 + j] = buf[k + j]
    return k + n


@njit(cache=True, _nrt=False)
def _transfer(plan, i, buf, k, bx, by, tx, ty, bonds, out):
    """Peer i's message, at ``buf[k:]``: pack my OWNED values into it (``out``), or unpack its values
    into my HALO copies: every rectangle's x then y, then each run of interface sites' travelling
    bond rows, one row after the other."""
    if out:
        segs, lo, hi = plan.ss, plan.ss_ptr[i], plan.ss_ptr[i + 1]
        sites, slo, shi = plan.sts, plan.sts_ptr[i], plan.sts_ptr[i + 1]
    else:
        segs, lo, hi = plan.rs, plan.rs_ptr[i], plan.rs_ptr[i + 1]
        sites, slo, shi = plan.rts, plan.rts_ptr[i], plan.rts_ptr[i + 1]
    for g in range(lo, hi):
        sg = segs[g]
        b, r, rows, j0, n = sg.block, sg.row, sg.rows, sg.j0, sg.n
        if b == BOTTOM:
            k = _rect(buf, k, bx, r, rows, j0, n, out)
            k = _rect(buf, k, by, r, rows, j0, n, out)
        else:
            k = _rect(buf, k, tx, r, rows, j0, n, out)
            k = _rect(buf, k, ty, r, rows, j0, n, out)
    for g in range(slo, shi):
        j0, n = sites[g].j0, sites[g].n
        for row in plan.travel:
            k = _move(buf, k, bonds, row, j0, n, out)


@njit(cache=True, _nrt=False)
def pack_all(plan, bx, by, tx, ty, bonds, out, repeats):
    """Pack every peer's message into the send buffer (``out``), or unpack every received one into the HALO
    copies, ``repeats`` times: what ``mpi_post`` and ``mpi_complete`` do besides MPI (the packing
    micro-benchmark times it in compiled code, as a call from Python costs microseconds itself)."""
    for _ in range(repeats):
        for i in range(plan.peer.shape[0]):
            if out:
                _transfer(plan, i, plan.sbuf, plan.sb_ptr[i], bx, by, tx, ty, bonds, out)
            else:
                _transfer(plan, i, plan.rbuf, plan.rb_ptr[i], bx, by, tx, ty, bonds, out)


@njit(cache=True, _nrt=False)
def mpi_reduce_max(plan, flags):
    """``flags`` becomes its element-wise MAX over all ranks (MPI_Allreduce); returns the MPI error code."""
    h = plan.handles
    err = mpi.allreduce(flags.ctypes.data, plan.rflags.ctypes.data, np.int32(flags.shape[0]), h[mpi.H_INT64],
                        h[mpi.H_MAX], h[mpi.H_COMM])
    for i in range(flags.shape[0]):
        flags[i] = plan.rflags[i]
    return err


# Messages up to this size (bytes) go whole at MPI_Start (eager: MPICH's shared memory takes up to 64 KiB in a
# cell, networks commonly 8 to 16 KiB), so a test while they travel moves nothing and costs a call (about half a
# microsecond on this host, 4 % of a 2-rank step of the README's main job).
EAGER_BYTES = 8192


@njit(cache=True, _nrt=False)
def mpi_progress(plan):
    """MPI_Testall on the posted requests, so MPI moves the messages while the loop computes; nothing when
    every message is small enough to have gone whole at MPI_Start (``EAGER_BYTES``), or none goes by MPI."""
    nreq = plan.req.shape[0]
    if nreq == 0:
        return 0
    largest = 0
    for i in range(plan.peer.shape[0]):
        if not plan.shared[i]:
            largest = max(largest, plan.sb_ptr[i + 1] - plan.sb_ptr[i], plan.rb_ptr[i + 1] - plan.rb_ptr[i])
    if largest * plan.rbuf.itemsize <= EAGER_BYTES:
        return 0
    return mpi.testall(np.int32(nreq), plan.req.ctypes.data, plan.rflags.ctypes.data, plan.status.ctypes.data)


@njit(cache=True, _nrt=False)
def mpi_post(plan, bx, by, tx, ty, bonds):
    """Pack every peer's message: a peer on this node's into this rank's window at this step's parity, then
    its flag set to the step's sequence number (a release store); the others' into the send buffer, then
    start the receives from and the sends to those in one call (persistent requests, ``MPI_Startall``);
    returns the MPI error code."""
    npeer = plan.peer.shape[0]
    if npeer == 0:
        return 0
    seq = plan.seq[0] + 1
    plan.seq[0] = seq
    par = seq & 1
    # Every shared line this step writes, asked for at once: the peer's copies leave its cache together,
    # not one line after the other as the stores reach each (a hint: it changes no value).
    line = max(64 // plan.node.itemsize, 1)
    for i in range(npeer):
        if plan.shared[i]:
            k0 = plan.dst[par, i]
            for k in range(k0, k0 + plan.sb_ptr[i + 1] - plan.sb_ptr[i], line):
                shm.prefetch_write(plan.node, k)
    out = np.bool_(True)                # a variable: one compiled _transfer for both directions
    for i in range(npeer):
        if plan.shared[i]:
            _transfer(plan, i, plan.node, plan.dst[par, i], bx, by, tx, ty, bonds, out)
            shm.store_release(plan.ready, plan.fdst[i], seq)
        else:
            _transfer(plan, i, plan.sbuf, plan.sb_ptr[i], bx, by, tx, ty, bonds, out)
    nreq = plan.req.shape[0]
    if nreq == 0:
        return 0
    return mpi.startall(np.int32(nreq), plan.req.ctypes.data)


@njit(cache=True, _nrt=False)
def mpi_complete(plan, bx, by, tx, ty, bonds):
    """Wait for what ``mpi_post`` started and unpack it into the HALO copies: the messages (MPI_Waitall),
    then from each on-node peer's window once its flag reads this step's sequence number (an acquire load);
    returns the MPI error code."""
    npeer = plan.peer.shape[0]
    if npeer == 0:
        return 0
    nreq = plan.req.shape[0]
    err = mpi.waitall(np.int32(nreq), plan.req.ctypes.data, plan.status.ctypes.data) if nreq else 0
    seq = plan.seq[0]
    par = seq & 1
    out = np.bool_(False)
    for i in range(npeer):
        if plan.shared[i]:
            shm.wait_for(plan.ready, plan.fsrc[i], seq)
            _transfer(plan, i, plan.node, plan.src[par, i], bx, by, tx, ty, bonds, out)
        else:
            _transfer(plan, i, plan.rbuf, plan.rb_ptr[i], bx, by, tx, ty, bonds, out)
    return err
