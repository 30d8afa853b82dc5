"""Slabs and halos that follow the interface's slip (``engine.follow``, ``parallel.layout.Drift``,
``parallel.migrate``).

Drawn: where a shifted block's slabs and halos stand, and that the halos cover every position the drift box
allows (the loop's own coverage check, at the box's corners) and no more than a link beyond it.  In
process: the migration by global id between two placements.  On the command line: 8 ranks on slabs a few
columns wide, with a slip of about 24 a that makes the halos follow it many times, bitwise the one-rank
run; checkpointed on 8 ranks and continued on 5.
"""
import itertools

import numpy as np
import pytest

from helpers import SMALL, datasets, require, run_cli, scene, small_toml
from parslip.engine.kernels.interface import Geometry, coverage
from parslip.model.lattice import BOTTOM, TOP, Lattice
from parslip.parallel.layout import (MASKED, PAD, Drift, build_layout, drift_reach, follow_box, link_of, start_box)
from parslip.parallel.migrate import NODES, SITES, Placement, block_columns, redistribute
from parslip.scene.derive import derive

QUANTA = 64


def _layouts(lat, ranks, drift, link=1):
    reach = drift_reach(link, drift)
    return [build_layout(lat, r, ranks, reach, "push") for r in range(ranks)]


def test_the_block_slabs_stand_over_the_substrate_slabs_they_slid_to_drawn():
    """A block of 20 columns over 40 substrate columns (block columns 10-29), slid 7 columns: on 4 ranks
    each rank owns the block columns that now stand over its substrate slab, x-column c + 7; every column
    of each block has exactly one owner; the first and last slabs reach on to the block's ends.

        x-column   0         10        20        30        40
        substrate  |=========|=========|=========|=========|
        block (D=7)                 |-------------------|        columns 10-29 at x = 17-36
    """
    lat = Lattice(3, 20, 3, 40)
    drift = Drift(7, (-1.0, 4.0), (-1.0, 4.0), (4.0, 1.0, 4.0, 1.0))
    lays = _layouts(lat, 4, drift)
    for b in (BOTTOM, TOP):
        owned = np.concatenate([np.arange(*lay.block_columns(b)) for lay in lays])
        blk = lat.blocks[b]
        assert np.array_equal(np.sort(owned), np.arange(blk.col0, blk.col0 + blk.cols)), b
    for lay in lays:
        x0, x1 = lay.col_range
        lo, hi = lay.block_columns(TOP)
        if hi > lo:          # every owned block column stands over the rank's slab, but at the ends
            assert (lo + 7 >= x0 or lay.rank == 0) and (hi + 7 <= x1 or lay.rank == 3)
        assert lay.offsets == (0, 7)
    # Node sets are the blocks' columns: ids ascending, none twice, all of them once over the ranks.
    from parslip.engine.state import State  # noqa: F401  (the state indexes exactly these)
    gids = np.concatenate([lat.nodes_in_block_columns((lay.block_columns(BOTTOM), lay.block_columns(TOP)))["gid"]
                           for lay in lays])
    assert np.array_equal(np.sort(gids), np.arange(lat.n_nodes))


def test_peers_agree_on_what_travels_and_stay_neighbours():
    """Whatever a rank sends a peer is what the peer receives from it, segment for segment, for a shifted block;
    and with slabs wider than the halos, a rank's peers are its two neighbours only, however far the block
    slid (here 37 columns: about a slab)."""
    lat = Lattice(4, 200, 3, 600)
    drift = Drift(37, (-1.5, 4.25), (-1.0, 4.0), (4.0, 1.0, 4.0, 1.0))
    lays = _layouts(lat, 8, drift)
    assert min(np.diff(lays[0].bounds)) > max(*lays[0].reach.top, *lays[0].reach.bottom)
    for lay in lays:
        assert {p.rank for p in lay.peers} <= {lay.rank - 1, lay.rank + 1}
        for p in lay.peers:
            back = next(q for q in lays[p.rank].peers if q.rank == lay.rank)
            assert [(s.block, s.row, s.lo, s.hi) for s in p.send] == [(s.block, s.row, s.lo, s.hi) for s in back.recv]
            assert p.send_sites == back.recv_sites


def _geometry(lay, lat, reach):
    tl, bl = lay.blocks[TOP], lay.blocks[BOTTOM]
    lo, hi = tl.j(tl.stored[0])
    br = bl.rows - 1
    blo, bhi = bl.j(bl.stored[br])
    bown0, bown1 = bl.j(bl.owned[br])
    town0, town1 = tl.j(tl.owned[0])
    return Geometry(tbase=tl.base, tlo=lo, thi=hi, town0=town0, town1=town1, bbase=bl.base, blo=blo, bhi=bhi,
                    bown0=bown0, bown1=bown1, brow=bl.prow(br), tfirst=tl.span[0], tlast=tl.span[1] - 1,
                    bcols=lat.bottom.cols, rigid=0, tcover=reach.top_cover, bcover=reach.bottom_cover)


@pytest.mark.parametrize("seed", range(3))
def test_the_halos_cover_every_position_the_box_allows_and_not_a_link_more(seed):
    """The loop's own coverage check (``kernels.interface.coverage``), at the drift box's corners: each
    interface row at a uniform drift of either edge of its range.  Every rank is covered at every corner;
    and with the box's ranges widened by two links (a drift the halos were not built for), some rank is not,
    so the formula is not merely generous."""
    rng = np.random.default_rng(seed)
    lat = Lattice(3, 50, 3, 120)
    link = link_of(0.5, 0.7)
    shift = int(rng.integers(-20, 30))
    t = sorted(rng.uniform(-3, 3, 2))
    b = sorted(rng.uniform(-1, 1, 2))
    drift = Drift(shift, (t[0], t[1]), (b[0], b[1]))
    reach = drift_reach(link, drift)
    lays = [build_layout(lat, r, 6, reach, "push") for r in range(6)]

    def covered(ut, ub):
        ok = []
        for lay in lays:
            tl, bl = lay.blocks[TOP], lay.blocks[BOTTOM]
            tx = np.full(tl.width, shift + ut)
            bx = np.full(bl.width, ub)
            ok.append(coverage(tx, bx, _geometry(lay, lat, reach)))
        return all(ok)
    for ut, ub in itertools.product(t, b):
        assert covered(ut, ub), (ut, ub)
    assert not all(covered(ut, ub) for ut, ub in [(t[1] + 2 * link, b[0]), (t[0] - 2 * link, b[1] + 0.0)])


def test_a_rebuild_centres_the_block_and_keeps_its_skins():
    """``follow_box``: the block's sites at u_x in [30.2, 33.9] (relative to D = 28: [2.2, 5.9]), the
    substrate's in [-0.1, 0.3]: the new D centres the block over the substrate, round(32.05 - 0.1) = 32;
    each edge gets its skin (4 a ahead, 1 behind), or four times its growth where that is more; edges on
    1/64 a."""
    old = Drift(28, (-1.0, 6.0), (-1.0, 4.0))
    extremes = (5.9, -2.2, 0.3, 0.1)                  # top hi, -top lo, bottom hi, -bottom lo (relative to D)
    new = follow_box(old, extremes, (2.0, 0.0, 0.0, 0.0), (1.0, 4.0), QUANTA)
    assert new.shift == 32
    assert new.top[1] == pytest.approx(33.9 - 32 + 8.0, abs=1 / QUANTA) and new.top[1] >= 33.9 - 32 + 8.0
    assert new.top[0] == pytest.approx(30.2 - 32 - 1.0, abs=1 / QUANTA) and new.top[0] <= 30.2 - 32 - 1.0
    assert new.bottom == (pytest.approx(-1.1, abs=1 / QUANTA), pytest.approx(4.3, abs=1 / QUANTA))
    assert new.skin == (8.0, 1.0, 4.0, 1.0)
    assert all(v * QUANTA == int(v * QUANTA) for v in (*new.top, *new.bottom))
    first = start_box((1.0, 4.0))
    assert first.shift == 0 and first.top == (-1.0, 4.0) and first.edges == (4.0, 1.0, 4.0, 1.0)


@pytest.mark.parallel(nprocs=3)
def test_migration_by_global_id_delivers_each_rank_what_it_owns():
    """Node and site tables held under one placement (no shift) are moved to a placement whose block stands
    11 columns on and whose slabs are cut anew, then back: each rank receives exactly the keys it owns, in
    order, each with its own values (a function of the key), and the round trip restores what it held."""
    from mpi4py import MPI
    comm = MPI.COMM_WORLD
    lat = Lattice(3, 30, 2, 60)
    reach0 = drift_reach(1, Drift(0, (-1.0, 4.0), (-1.0, 4.0)))
    reach1 = drift_reach(1, Drift(11, (-1.0, 4.0), (-1.0, 4.0)))
    a = build_layout(lat, comm.rank, comm.size, reach0)
    b = build_layout(lat, comm.rank, comm.size, reach1)
    pa, pb = Placement(a.bounds, a.offsets), Placement(b.bounds, b.offsets)

    def held(lay):
        nodes = lat.nodes_in_block_columns((lay.block_columns(BOTTOM), lay.block_columns(TOP)))["gid"]
        lo, hi = lay.block_columns(TOP)
        return nodes, np.arange(lo, hi) - lat.top.col0

    nodes, sites = held(a)
    tables = {"n": (NODES, nodes, {"v": np.stack([nodes * 1.5, -nodes], 1)}),
              "s": (SITES, sites, {"w": sites * 2.0 + 0.25})}
    got = redistribute(comm, lat, pa, pb, tables)
    want_nodes, want_sites = held(b)
    assert np.array_equal(got["n"][1], want_nodes) and np.array_equal(got["s"][1], want_sites)
    assert np.array_equal(got["n"][2]["v"], np.stack([want_nodes * 1.5, -want_nodes], 1))
    assert np.array_equal(got["s"][2]["w"], want_sites * 2.0 + 0.25)
    assert a.bounds.tolist() != b.bounds.tolist()          # the slabs were cut anew for the shifted block
    back = redistribute(comm, lat, pb, pa, got)
    assert np.array_equal(back["n"][1], nodes) and np.array_equal(back["n"][2]["v"], tables["n"][2]["v"])
    assert np.array_equal(back["s"][2]["w"], tables["s"][2]["w"])
    for p in range(comm.size):          # ownership is a partition of the columns in both placements
        assert block_columns(lat, pb, p, TOP) == b.block_columns(TOP) or p != comm.rank


# A long slip on narrow slabs: SMALL's block (24 columns) on 80 substrate columns, driven at 0.1 c_r for
# 10 l/c_r: it slides about 24 a, many times the skin, over slabs of 4-9 columns on 8 ranks.  The load settles
# for 1 l/c_r (SMALL's 2 would add 312 steps to every run): 3592 steps, not 7029 at 0.05 c_r for 20 l/c_r
# (the same slip).
LONG = {**SMALL, "lattice.bottom_cols": 80, "load.settle": 1.0, "drive.v0": 0.1, "drive.duration": 10.0,
        "output.snapshots": 4, "output.buffer_frames": 16}
HALF = {"drive.duration": LONG["drive.duration"] / 2, "checkpoint.every": 1.0}     # the block slid 12 a
LIMIT_S = 300


@pytest.fixture(scope="module")
def long_slip(tmp_path_factory):
    require("gather")
    d = tmp_path_factory.mktemp("follow")
    sc = d / "long.toml"
    sc.write_text(small_toml(**LONG))
    out = d / "r1.vtkhdf"
    p = run_cli(1, "run", sc, "--out", out, "--no-png", "--quiet", timeout=LIMIT_S)
    assert p.returncode == 0, p.stderr
    return sc, d, datasets(out)[0]


def _sets(over: dict) -> list[str]:
    return [a for k, v in over.items() for a in ("--set", f"{k}={v}")]


def _assert_same(got, ref, what, groups=("interface/", "energy/", "VTKHDF/")):
    names = [n for n in ref if n.startswith(groups)]
    assert names and set(names) <= set(got), what
    for name in names:
        assert got[name].tobytes() == ref[name].tobytes(), (what, name)


def test_eight_narrow_slabs_follow_a_long_slip_bitwise(long_slip):
    """8 ranks: the halos are rebuilt many times as the block slides about 24 a over slabs of 4 to 9 columns
    (under the block; the outer two hold bare substrate), and every /interface, /energy and snapshot dataset
    is the one-rank run's, bit for bit."""
    sc, d, ref = long_slip
    st = derive(scene(**LONG))
    lay = build_layout(st.lattice, 0, 8, st.reach)
    assert max(np.diff(lay.bounds)[1:-1]) < 10 and st.v0 * st.n_drive * st.dt > 20
    out = d / "r8.vtkhdf"
    p = run_cli(8, "run", sc, "--out", out, "--no-png", "--watchdog", "60", timeout=LIMIT_S)
    assert p.returncode == 0, p.stderr[-3000:]
    rebuilds = [line for line in p.stderr.splitlines() if "interface halo:" in line]
    assert rebuilds and int(rebuilds[0].split("interface halo:")[1].split()[0]) >= 4, rebuilds
    _assert_same(datasets(out)[0], ref, "8 ranks")


def test_a_checkpoint_of_a_slid_block_restarts_on_another_rank_count(long_slip):
    """Half the run on 8 ranks (the block slid 12 a: its slabs stand shifted), a checkpoint, the rest on 5:
    the interface record and the energy budget are the one-rank run's, bit for bit (the snapshots fall where
    the first half's shorter duration put them)."""
    sc, d, ref = long_slip
    out = d / "r8_5.vtkhdf"
    p = run_cli(8, "run", sc, "--out", out, "--no-png", "--quiet", *_sets(HALF), "--watchdog", "60",
                timeout=LIMIT_S)
    assert p.returncode == 0, p.stderr[-3000:]
    p = run_cli(5, "run", sc, "--out", out, "--no-png", "--restart", f"{out}.ckpt.h5", "--watchdog", "60",
                timeout=LIMIT_S)
    assert p.returncode == 0, p.stderr[-3000:]
    _assert_same(datasets(out)[0], ref, "8 ranks, then 5", ("interface/", "energy/"))


def test_a_one_rank_checkpoint_of_a_slid_block_continues_on_three(long_slip):
    """A checkpoint written on one rank, whose halos never followed anything, of a block slid 12 a (more than
    the skin): 3 ranks build the drift box of the slip the state holds, migrate to it, and continue the
    one-rank run bit for bit."""
    sc, d, ref = long_slip
    out = d / "r1_3.vtkhdf"
    p = run_cli(1, "run", sc, "--out", out, "--no-png", "--quiet", *_sets(HALF), timeout=LIMIT_S)
    assert p.returncode == 0, p.stderr[-3000:]
    p = run_cli(3, "run", sc, "--out", out, "--no-png", "--restart", f"{out}.ckpt.h5", "--watchdog", "60",
                timeout=LIMIT_S)
    assert p.returncode == 0, p.stderr[-3000:]
    _assert_same(datasets(out)[0], ref, "1 rank, then 3", ("interface/", "energy/"))


@pytest.mark.parametrize("case", range(12))
def test_counts_in_closed_form_are_the_layouts_counts(case):
    """``parallel.counts.rank_counts`` (every rank at once, no layout built) gives each rank's nodes, sites,
    halo values sent and received, peers, farthest hop, array cells, and the loop's row segments and single-node
    tasks exactly as its own layout does, for shifted blocks, multi-hop halos (slabs narrower than the halos), a
    rigid substrate and a free block."""
    from parslip.parallel.counts import rank_counts
    from parslip.studies.bench.scaling import rank_share
    rng = np.random.default_rng(case)
    lat = [Lattice(3, 30, 4, 90), Lattice(3, 30, 1, 90, substrate="rigid"), Lattice(4, 25, 0, 0)][case % 3]
    ranks = int(rng.integers(2, 11))
    shift = int(rng.integers(-12, 25)) if lat.has_interface else 0
    drift = Drift(shift, tuple(sorted(rng.uniform(-3, 6, 2))), tuple(sorted(rng.uniform(-1, 1, 2))))
    reach = drift_reach(int(rng.integers(1, 3)), drift)
    lays = [build_layout(lat, r, ranks, reach, "push") for r in range(ranks)]
    c = rank_counts(lat, lays[0].bounds, reach, lays[0].offsets)
    for lay in lays:
        share = rank_share(lat, lay)
        r = lay.rank
        assert (c.nodes[r], c.sites[r]) == (share.nodes, share.sites), r
        assert (c.sent[r], c.received[r]) == (share.values_sent, share.values_received), r
        assert c.peers[r] == len(share.peers) and c.hops[r] == share.hops, r
        single = lay.tasks["kind"] == MASKED
        rows = lay.tasks["rows"]                  # a task may cover several rows: count row segments and nodes
        assert (c.segments[r], c.singles[r]) == (int(rows[~single].sum()), int(rows[single].sum())), r
        for i, b in enumerate(lay.blocks):
            if b.rows:
                assert c.cells[i][r] == int(np.prod(b.shape)), (r, i)
        if lat.has_interface:
            assert tuple(c.halo_top[r]) == share.halo_top and (lat.rigid or tuple(c.halo_bottom[r]) == share.halo_bottom)
