"""The run as a library call: ``parslip.run`` writes what ``parslip run`` writes, bit for bit.

From a plain script (a subprocess, as a user would), with the scene as a path or a mapping and the
overrides as a mapping or as KEY=VALUE strings; on two ranks with ``comm``; with its documented
exceptions (bad input: ConfigError; a failed run: RunError, the file marked failed); a stop and a
restart through the API; and without MPI: a one-rank run and all analysis load no MPI library.
"""
import os
import sys
import textwrap

import h5py
import numpy as np
import pytest

import parslip
from helpers import SMALL, WHEEL_MPIEXEC, cli_env, datasets, reference_run, require, run_limited, scene

# What a run writes about how and when it ran, which may differ between two runs of the same scene.
PROVENANCE = {"command", "created_utc", "run_id", "scene_file", "git_commit", "host"}
SHORT = {"drive.duration": 4.0, "output.snapshots": 2}


def assert_same_run(a, b, differ=()):
    da, aa = datasets(a)
    db, ab = datasets(b)
    assert da.keys() == db.keys()
    for k in da:
        assert da[k].dtype == db[k].dtype and da[k].tobytes() == db[k].tobytes(), k
    keys = {k for k in aa if not k.startswith("timing_")} - PROVENANCE - set(differ)
    assert keys == {k for k in ab if not k.startswith("timing_")} - PROVENANCE - set(differ)
    for k in keys:
        assert np.array_equal(aa[k], ab[k]), k


@pytest.fixture(scope="module")
def cli_run(tmp_path_factory):
    return reference_run(tmp_path_factory.mktemp("api"), SHORT, "--set", "drive.v0=0.03")


def _script(code: str, tmp, timeout=300, ranks=None):
    path = tmp / "script.py"
    path.write_text(textwrap.dedent(code))
    cmd = [sys.executable, str(path)]
    if ranks:
        cmd = [WHEEL_MPIEXEC, "-n", str(ranks)] + cmd
    p = run_limited(cmd, env=cli_env(), timeout=timeout, cwd=tmp)
    assert p.returncode == 0, p.stderr[-3000:]
    return p


def test_a_plain_script_writes_what_the_command_line_writes(tmp_path, cli_run):
    sc, ref = cli_run
    p = _script(f"""
        import sys
        import parslip
        run = parslip.run({str(sc)!r}, out="api.vtkhdf", sets={{"drive.v0": 0.03}}, progress=False)
        assert run.outcome.complete and run.status == "complete"
        assert run.path == "api.vtkhdf" and len(run.times) > 10 and run.fronts()
        print("mpi" + str([m for m in sys.modules if m.startswith("mpi4py")]))
        maps = open("/proc/self/maps").read()
        print("libmpi" + str(any(x in maps for x in ("libmpi.", "libmpich."))))
    """, tmp_path)
    assert "mpi[]" in p.stdout and "libmpiFalse" in p.stdout, p.stdout      # one rank: no MPI at all
    assert_same_run(tmp_path / "api.vtkhdf", ref)


def test_scene_as_a_mapping_and_overrides_as_strings(tmp_path, cli_run):
    sc, ref = cli_run
    flat = {**SMALL, **SHORT}
    nested = {}
    for k, v in flat.items():
        sec, key = k.split(".", 1)
        nested.setdefault(sec, {})[key] = v
    a = parslip.run(flat, out=tmp_path / "flat.vtkhdf", sets=["drive.v0=0.03"], progress=False)
    b = parslip.run(nested, out=tmp_path / "nested.vtkhdf", sets={"drive.v0": 0.03}, progress=False)
    assert_same_run(a.path, ref)
    assert_same_run(b.path, ref)


def test_documented_exceptions(tmp_path, monkeypatch):
    with pytest.raises(parslip.ConfigError, match=r"drive\.vv = 1: unknown key"):
        parslip.run({"drive.vv": 1}, out=tmp_path / "a.vtkhdf")
    with pytest.raises(parslip.ConfigError, match="needs an output path"):
        parslip.run({}, out=None)
    (tmp_path / "exists.vtkhdf").write_text("")
    with pytest.raises(parslip.ConfigError, match="exists; accepted"):
        parslip.run({**SMALL}, out=tmp_path / "exists.vtkhdf")
    # A failed run: a stale omega_max in the cache puts dt above the stability limit.
    from parslip.io import cache
    from parslip.scene.derive import derive
    monkeypatch.setenv("PARSLIP_CACHE_DIR", str(tmp_path / "cache"))
    over = {**SMALL, "load.FN": 0.0, "load.ramp": 0.0, "load.settle": 0.0, "drive.duration": 3.0,
            "output.snapshots": 0}
    st = derive(scene(**over))
    lat, mat = st.lattice, st.material
    b, t = lat.blocks
    key = cache.key(top=[t.rows, t.cols], bottom=[b.rows, b.cols], substrate=lat.substrate,
                    kn=[mat.kn_bottom, mat.kn_top], kt=[mat.kt_bottom, mat.kt_top], kx=0.1, ky=0.3)
    cache.store(key, (st.omega_max / 1.2, "lanczos"))
    out = tmp_path / "failed.vtkhdf"
    with pytest.raises(parslip.RunError, match="grew without bound|non-finite"):
        parslip.run(over, out=out, progress=False)
    assert parslip.open(str(out)).status.startswith("failed: state ")


def test_stop_and_continue_through_the_api(tmp_path, cli_run):
    """stop_after=0: the run checkpoints at its first agreement and returns; restart="auto" finishes it,
    bitwise the uninterrupted run."""
    sc, ref = cli_run
    out = tmp_path / "stopped.vtkhdf"
    first = parslip.run(sc, out=out, sets={"drive.v0": 0.03}, stop_after=0.0, progress=False)
    assert first.outcome.status.startswith("checkpointed at step") and os.path.exists(first.outcome.checkpoint)
    done = parslip.run(sc, out=out, sets={"drive.v0": 0.03}, restart="auto", progress=False)
    assert done.outcome.complete
    a, _ = datasets(out)
    b, _ = datasets(ref)
    for k in b:
        if k.startswith("interface/"):
            assert a[k].tobytes() == b[k].tobytes(), k
    again = parslip.run(sc, out=out, sets={"drive.v0": 0.03}, restart="auto", progress=False)
    assert again.outcome.complete and again.outcome.step == 0          # complete already: nothing to do


def test_two_ranks_through_comm(tmp_path, cli_run):
    require("gather")
    sc, ref = cli_run
    _script(f"""
        from mpi4py import MPI
        import parslip
        run = parslip.run({str(sc)!r}, out="two.vtkhdf", sets=["drive.v0=0.03"], comm=MPI.COMM_WORLD,
                          progress=False)
        assert run.outcome.size == 2 and run.outcome.complete
    """, tmp_path, ranks=2)
    assert_same_run(tmp_path / "two.vtkhdf", ref, differ=("n_ranks",))
    with h5py.File(tmp_path / "two.vtkhdf", "r") as f:
        assert f.attrs["n_ranks"] == 2


def test_analysis_loads_no_mpi(tmp_path, cli_run):
    _, ref = cli_run
    p = _script(f"""
        import sys
        import parslip
        from parslip.plot import figures
        run = parslip.open({str(ref)!r})
        run.fronts(); run.interface; run.timings
        figures.write_all(run, "figs", only=["spacetime"])
        print("mpi" + str([m for m in sys.modules if m.startswith("mpi4py")]))
    """, tmp_path)
    assert "mpi[]" in p.stdout
