"""Parallel runs against serial runs, compared by global node id.

The in-process tests run under mpi-pytest on 2 ranks; the rank-count tests
launch the real command line under mpiexec on 1, 2, 3 (and more, oversubscribed)
ranks and compare the output files bit for bit.
"""
import os
import shutil
import subprocess
import sys

import h5py
import numpy as np
import pytest

from helpers import SMALL, scene, small_toml
from parslip.engine.simulation import Simulation
from parslip.model.lattice import Lattice
from parslip.parallel.exchange import COMPLETE, POST, build_plan, exchange
from parslip.parallel.layout import PAD, build_layout, column_cost, interface_reach, partition
from parslip.scene.derive import derive

MPIEXEC = shutil.which("mpiexec")


def _gids(lat, lay, b):
    """Global id of every array cell of block b on this rank (-1 for ghost cells)."""
    B = lay.blocks[b]
    rows, cols = np.meshgrid(np.arange(B.shape[0]) - PAD, np.arange(B.width) + B.base, indexing="ij")
    return lat.gid(np.full(rows.shape, b), rows, cols)


@pytest.mark.parallel(nprocs=2)
def test_halo_exchange_by_global_id():
    """A 4-row free strip of 10 columns cut at column 5 (bulk rows only: a halo of one column).

        column      0 1 2 3 4 | 5 6 7 8 9
        rank 0      O O O O O | H              O owned, H halo copy
        rank 1              H | O O O O O

    After the exchange every halo copy holds its owner's value (here 1000 + gid)
    and no other cell changed.
    """
    from mpi4py import MPI
    comm = MPI.COMM_WORLD
    lat = Lattice(4, 10, 0, 0)
    lay = build_layout(lat, comm.rank, comm.size, interface_reach(0.5, 0.7, 0.0))
    assert lay.col_range == ((0, 5) if comm.rank == 0 else (5, 10))
    plan = build_plan(lay, np.float64, comm)
    gid = _gids(lat, lay, 1)
    B = lay.blocks[1]
    cols = np.arange(B.width) + B.base
    lo, hi = lay.col_range
    owned = (gid >= 0) & (cols[None, :] >= lo) & (cols[None, :] < hi)
    tx = np.where(owned, 1000.0 + gid, -1.0)
    ty = -tx
    e = np.zeros((0, 0))
    assert exchange(POST, plan, e, e, tx, ty, np.zeros(B.width, np.int64), np.zeros(B.width), np.zeros(8, np.int64)) == 0
    assert exchange(COMPLETE, plan, e, e, tx, ty, np.zeros(B.width, np.int64), np.zeros(B.width),
                    np.zeros(8, np.int64)) == 0
    halo_col = 5 if comm.rank == 0 else 4
    halo = (gid >= 0) & (cols[None, :] == halo_col)
    assert halo.sum() == 4
    np.testing.assert_array_equal(tx[halo], 1000.0 + gid[halo])
    np.testing.assert_array_equal(ty[halo], -1000.0 - gid[halo])
    np.testing.assert_array_equal(tx[~halo & ~owned], -1.0)            # ghost and unneeded cells untouched


@pytest.mark.parallel(nprocs=2)
def test_parallel_state_matches_serial_by_global_id():
    """Two ranks and one rank agree to the bit on every node, after bonds broke and re-formed."""
    from mpi4py import MPI
    comm = MPI.COMM_WORLD
    sc = scene(**SMALL)
    st = derive(sc)
    par = Simulation(st, comm)
    ser = Simulation(derive(sc, (st.omega_max, st.omega_method)))
    n = st.n_drive_start + int(0.8 * st.n_drive)
    par.run(until=n)
    ser.run(until=n)
    total = comm.allreduce(int(par.counters[0]))
    assert total > 5 and total == ser.counters[0]
    pos = np.searchsorted(ser.state.gid, par.state.gid)
    np.testing.assert_array_equal(par.u, ser.u[pos])
    np.testing.assert_array_equal(par.u_prev, ser.u_prev[pos])
    s = par.state.site0()
    np.testing.assert_array_equal(par.state.owned_partner(), ser.state.owned_partner()[s:s + len(par.state.owned_partner())])


def _mpirun(n, scene_file, out, *extra):
    """The real command line on n ranks; returns the finished process."""
    return subprocess.run([MPIEXEC, "-n", str(n), sys.executable, "-m", "parslip", "run", str(scene_file),
                           "--out", str(out), "--no-png", "--quiet", *extra], capture_output=True, text=True,
                          timeout=300)


def _datasets(path):
    out = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: out.__setitem__(name, obj[...]) if isinstance(obj, h5py.Dataset) else None)
        attrs = dict(f.attrs)
    return out, attrs


def _same(files, ref_n):
    ref, _ = files[ref_n]
    for n, (data, attrs) in files.items():
        assert attrs["n_ranks"] == n and attrs["status"] == "complete"
        assert data.keys() == ref.keys()
        for name in ref:
            assert data[name].dtype == ref[name].dtype and data[name].tobytes() == ref[name].tobytes(), (n, name)


@pytest.mark.skipif(MPIEXEC is None, reason="needs mpiexec")
def test_output_bitwise_identical_with_ranks_that_hold_no_interface(tmp_path):
    """The substrate overhangs the block 12:1 on each side, so on 3 ranks the outer
    slabs hold no interface site of the block, not even as a halo copy: they must
    still take part in every exchange."""
    over = {"lattice.top_cols": 12, "lattice.bottom_cols": 300, "drive.v0": 0.02, "drive.duration": 4.0}
    sc = tmp_path / "overhang.toml"
    sc.write_text(small_toml(**over))
    st = derive(scene(**{**SMALL, **over}))
    for rank in (0, 2):
        top = build_layout(st.lattice, rank, 3, st.reach).blocks[1]
        assert (top.stored[:, 1] <= top.stored[:, 0]).all()
    files = {n: _datasets(tmp_path / f"o{n}.vtkhdf") for n in (1, 3)
             if _mpirun(n, sc, tmp_path / f"o{n}.vtkhdf").returncode == 0}
    assert set(files) == {1, 3}
    assert (files[1][0]["interface/intact"] == 0).any()
    _same(files, 1)


@pytest.mark.skipif(MPIEXEC is None, reason="needs mpiexec")
def test_output_bitwise_identical_on_1_2_3_ranks(tmp_path):
    sc = tmp_path / "small.toml"
    sc.write_text(small_toml())
    files = {}
    for n in (1, 2, 3):
        out = tmp_path / f"r{n}.vtkhdf"
        p = _mpirun(n, sc, out)
        assert p.returncode == 0, p.stderr
        files[n] = _datasets(out)
    _same(files, 1)

    # The test must exercise the hard case: a bond that broke and re-formed
    # with its top node and its new bottom partner on different ranks.
    st = derive(scene(**SMALL))
    intact, partner = files[1][0]["interface/intact"], files[1][0]["interface/partner"]
    crossed = {}
    for n in (2, 3):
        bounds = partition(column_cost(st.lattice), n)
        owner = lambda col: np.searchsorted(bounds, col, side="right") - 1   # noqa: E731
        top_owner = owner(st.lattice.top.col0 + np.arange(st.lattice.top.cols))
        was_broken = np.maximum.accumulate(intact == 0, axis=0)
        rebonded = (intact == 1) & was_broken
        across = rebonded & (owner(np.maximum(partner, 0)) != top_owner[None, :])
        crossed[n] = int(across.sum())
    assert crossed[2] > 0 and crossed[3] > 0, crossed


@pytest.mark.skipif(MPIEXEC is None, reason="needs mpiexec")
def test_slabs_narrower_than_the_slip_are_bitwise_identical(tmp_path):
    """Eight ranks on 40 columns: slabs of 3 to 7 columns, narrower than the halos the slip needs
    (14 to 16 columns), so halos reach across several slabs (multi-hop)."""
    sc = tmp_path / "small.toml"
    sc.write_text(small_toml())
    st = derive(scene(**SMALL))
    lay = build_layout(st.lattice, 0, 8, st.reach)
    assert max(np.diff(lay.bounds)) < st.reach.bottom_site and len(lay.peers) >= 3
    files = {}
    for n in (1, 8):
        out = tmp_path / f"r{n}.vtkhdf"
        p = _mpirun(n, sc, out)
        assert p.returncode == 0, p.stderr
        files[n] = _datasets(out)
    _same(files, 1)


@pytest.mark.skipif(MPIEXEC is None or not h5py.get_config().mpi,
                    reason="needs an MPI-enabled h5py (parallel HDF5); PyPI's h5py is serial")
def test_collective_mpio_output_matches_serial(tmp_path):
    """With parallel HDF5 every rank writes its own slices through the mpio driver."""
    sc = tmp_path / "small.toml"
    sc.write_text(small_toml())
    files = {}
    for n in (1, 2):
        out = tmp_path / f"r{n}.vtkhdf"
        p = _mpirun(n, sc, out)
        assert p.returncode == 0, p.stderr
        files[n] = _datasets(out)
    assert files[2][1]["hdf5_mode"] == "mpio"
    for name, ref in files[1][0].items():
        assert files[2][0][name].tobytes() == ref.tobytes(), name


@pytest.mark.skipif(MPIEXEC is None, reason="needs mpiexec")
def test_slip_beyond_the_halo_stops_the_run(tmp_path):
    """The halo serves interface.slip_reach; sliding further is refused, not wrong.

    At v0 = 0.05 c_r the block's interface slides about 7 a in 6 l/c_r; halos sized for 0.2 a
    (plus the interface's own reach) stop serving it about halfway."""
    sc = tmp_path / "small.toml"
    sc.write_text(small_toml(**{"interface.slip_reach": 0.2, "drive.v0": 0.05}))
    out = tmp_path / "o.vtkhdf"
    p = _mpirun(2, sc, out)
    assert p.returncode == 3, p.stderr
    assert "interface.slip_reach" in p.stderr and "Traceback" not in p.stderr
    with h5py.File(out, "r") as f:
        assert f.attrs["status"].startswith("failed: interface slip reached")
