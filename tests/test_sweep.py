"""`parslip sweep` and `parslip map`: the sweep file, the points and their dealing, failing points, resuming
after a kill, groups of ranks under MPI, the summary table (CSV and netCDF), and the map.

Scenes are SMALL (24-site contact) driven for a few l/c_r: a point takes a fraction of a second.
Multi-rank runs go through ``helpers.run_cli`` (a hard time limit)."""
import csv
import json
import os
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
import pytest

import parslip
from helpers import cli_env, datasets, small_toml
from parslip.cli import main
from parslip.io.contract import put_status, read_status
from parslip.studies import sweep as S

TINY = {"drive.duration": 3.0, "output.snapshots": 0}


@pytest.fixture
def here(tmp_path, monkeypatch):
    """A working directory with the tiny base scene, and an omega_max cache of its own."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("PARSLIP_CACHE_DIR", str(tmp_path / "cache"))
    (tmp_path / "tiny.toml").write_text(small_toml(**TINY))
    return tmp_path


def _write(path, text):
    path.write_text(text)
    return str(path)


GRID = """base = "tiny.toml"
[set]
"drive.v0" = 0.02
[grid]
"drive.mode" = ["push", "shear"]
"load.FN" = [1.0, -1.0]
[zip]
"interface.kx" = [0.1, 0.2]
"interface.ky" = [0.3, 0.6]
"""


# ------------------------------------------------------------------------------ the sweep file --

def test_points_in_grid_then_zip_order(here):
    sw = S.load_sweep(_write(here / "s.toml", GRID))
    assert sw.swept == ["drive.mode", "load.FN", "interface.kx", "interface.ky"]
    assert len(sw.points) == 8 and [p.name for p in sw.points[:2]] == ["p000", "p001"]
    first = [(p.swept["drive.mode"], p.swept["load.FN"], p.swept["interface.kx"], p.swept["interface.ky"])
             for p in sw.points[:4]]
    assert first == [("push", 1.0, 0.1, 0.3), ("push", 1.0, 0.2, 0.6), ("push", -1.0, 0.1, 0.3),
                     ("push", -1.0, 0.2, 0.6)]
    assert all(p.sets["drive.v0"] == 0.02 for p in sw.points)
    # a sweep without [grid] or [zip] is the one point of base + [set]; nested TOML tables work too
    one = S.load_sweep(_write(here / "one.toml", 'base = "tiny.toml"\n[set.drive]\nv0 = 0.03\n'))
    assert len(one.points) == 1 and one.points[0].sets == {"drive.v0": 0.03} and one.swept == []


def test_dealing_is_longest_first_to_the_least_loaded_and_deterministic():
    assert S.deal([1, 1, 1, 1, 1, 1, 1, 1], 2) == [[0, 2, 4, 6], [1, 3, 5, 7]]
    assert S.deal([5, 1, 1, 1, 1, 1], 2) == [[0], [1, 2, 3, 4, 5]]
    assert S.deal([3, 3, 2, 2, 2], 2) == [[0, 2, 4], [1, 3]]
    assert S.deal([], 3) == [[], [], []]


@pytest.mark.parametrize("text,message", [
    ('base = "tiny.toml"\nbogus = 1\n', "bogus = 1: unknown key; accepted: base, ranks_per_point, set, grid, zip"),
    ('ranks_per_point = 1\n', "base = None: accepted: the path of a scene file"),
    ('base = "nope.toml"\n', "base = 'nope.toml': no such file"),
    ('base = "tiny.toml"\nranks_per_point = 0\n', "ranks_per_point = 0: accepted: an integer >= 1"),
    ('base = "tiny.toml"\n[grid]\n"load.FN" = 1.0\n', "[grid] load.FN = 1.0: accepted: a non-empty list"),
    ('base = "tiny.toml"\n[grid]\n"load.fn" = [1.0]\n',
     "[grid] load.fn = [1.0]: unknown scene key (did you mean load.FN?)"),
    ('base = "tiny.toml"\n[zip]\n"interface.kx" = [0.1, 0.2]\n"interface.ky" = [0.3]\n',
     "[zip] lists of lengths {'interface.kx': 2, 'interface.ky': 1}: accepted: lists of one length"),
    ('base = "tiny.toml"\n[set]\n"load.FN" = 1.0\n[grid]\n"load.FN" = [1.0]\n',
     "[grid] load.FN: also in [set]; accepted: each key in one of [set], [grid], [zip]"),
    ('base = "tiny.toml"\n[set]\n"load.FN" = -2.0\n', "load.FN = -2.0: out of range"),
    ('base = "tiny.toml"\n[set]\n"drive.v0" = [1, 2]\n', "[set] drive.v0 = [1, 2]: accepted: one value"),
    ('base = "tiny.toml\n', "malformed TOML"),
])
def test_bad_sweep_files_are_one_line_and_exit_2(here, capsys, text, message):
    path = _write(here / "bad.toml", text)
    assert main(["sweep", path, "-o", str(here / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err, err
    assert not (here / "o" / "summary.csv").exists()


def test_bad_shard_and_a_rank_count_the_groups_do_not_divide(here, capsys):
    path = _write(here / "s.toml", GRID)
    assert main(["sweep", path, "-o", "o", "--shard", "2/2"]) == 2
    assert "--shard '2/2': accepted: I/N with 0 <= I < N" in capsys.readouterr().err
    two = _write(here / "two.toml", GRID.replace('base = "tiny.toml"', 'base = "tiny.toml"\nranks_per_point = 2'))
    assert main(["sweep", two, "-o", "o2"]) == 2
    assert "ranks_per_point = 2: the job has 1 rank(s); accepted: a rank count that is a multiple" in \
        capsys.readouterr().err


def test_another_sweep_in_the_same_outdir_is_refused(here, capsys):
    a = _write(here / "a.toml", 'base = "tiny.toml"\n[grid]\n"drive.v0" = [0.02]\n')
    b = _write(here / "b.toml", 'base = "tiny.toml"\n[grid]\n"drive.v0" = [0.03]\n')
    assert main(["sweep", a, "-o", "o", "--quiet"]) == 0
    assert main(["sweep", b, "-o", "o"]) == 2
    err = capsys.readouterr().err
    assert "-o 'o': holds another sweep" in err and "its points differ from this file's" in err
    c = _write(here / "c.toml", 'base = "tiny.toml"\n[set]\n"drive.duration" = 2.0\n[grid]\n"drive.v0" = [0.02]\n')
    assert main(["sweep", c, "-o", "o"]) == 2
    assert "its set differ from this file's" in capsys.readouterr().err


# --------------------------------------------------------------------------- running, one rank --

def _stale_omega(here, kx, ky):
    """Store omega_max / 1.2 for the tiny scene with this interface stiffness: its dt is then 8 % above
    the stability limit and its state grows without bound (a real non-finite run)."""
    from parslip.io import cache
    from parslip.scene.derive import derive
    from parslip.scene.load import load
    st = derive(load("tiny.toml", {"interface.kx": kx, "interface.ky": ky}))
    lat, mat = st.lattice, st.material
    b, t = lat.blocks
    key = cache.key(top=[t.rows, t.cols], bottom=[b.rows, b.cols], substrate=lat.substrate,
                    kn=[mat.kn_bottom, mat.kn_top], kt=[mat.kt_bottom, mat.kt_top], kx=kx, ky=ky)
    cache.store(key, (st.omega_max / 1.2, "lanczos"))


def _csv(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_sweep_runs_every_point_records_failures_and_writes_the_table(here, capsys):
    _stale_omega(here, 0.2, 0.6)
    path = _write(here / "s.toml", GRID)
    assert main(["sweep", path, "-o", "out"]) == 0
    cap = capsys.readouterr()
    assert "8 points: 2 ok, 6 failed, 0 pending" in cap.out
    rows = _csv(here / "out" / "summary.csv")
    assert list(rows[0])[:6] == ["point", "drive.mode", "load.FN", "interface.kx", "interface.ky", "status"]
    for key in ("first_break_time", "first_break_x", "mu_s", "rupture_kind", "n_fronts", "n_precursors",
                "front_speed", "front_speed_mean", "slip_per_event", "wall_s", "scene", "commit"):
        assert key in rows[0]
    by = {(r["drive.mode"], float(r["load.FN"]), float(r["interface.kx"])): r for r in rows}
    for mode in ("push", "shear"):
        ok = by[(mode, 1.0, 0.1)]
        assert ok["status"] == "ok"
        run = parslip.open(str(here / "out" / ok["out"]))
        obs = run.observables()
        assert float(ok["mu_s"]) == obs["mu_s"] and float(ok["first_break_time"]) == obs["first_break_time"]
        assert int(ok["n_fronts"]) == obs["n_fronts"] and ok["rupture_kind"] == obs["rupture_kind"]
        assert json.loads(ok["scene"]) == run.scene and run.scene["drive.mode"] == mode
        assert ok["commit"] == run.attrs["git_commit"] and float(ok["wall_s"]) > 0
        # a bad value: failed with the loader's line, naming the key, the value and what is accepted
        bad = by[(mode, -1.0, 0.1)]
        assert bad["status"] == "failed: load.FN = -1.0: out of range (in m c^2/a); accepted: >= 0"
        assert bad["mu_s"] == "" and bad["scene"] == ""
        # a state that grew without bound: failed with the run's line, and its file says so too
        nf = by[(mode, 1.0, 0.2)]
        assert nf["status"].startswith("failed: state grew without bound: at step") and "node" in nf["status"]
        with h5py.File(here / "out" / nf["out"], "r") as f:
            assert read_status(f).startswith("failed: state grew without bound")
    assert "Traceback" not in cap.err
    # The typed table: the same rows, numbers as numbers, through xarray and pandas.
    xr = pytest.importorskip("xarray")
    ds = xr.open_dataset(here / "out" / "summary.nc")
    assert ds["load.FN"].dtype == np.float64 and ds["drive.mode"].values.tolist()[:1] == ["push"]
    assert list(ds["point"].values) == [r["point"] for r in rows]
    np.testing.assert_array_equal(ds["mu_s"].values, [float(r["mu_s"] or "nan") for r in rows])
    assert ds["n_fronts"].values[0] == int(rows[0]["n_fronts"]) and np.isnan(ds["n_fronts"].values[2])
    assert ds["mu_s"].attrs["units"] == "-" and ds["first_break_time"].attrs["units"] == "l/c_r"
    df = ds.to_dataframe()
    assert df.loc["p000", "status"] == "ok" and df["status"].str.startswith("failed").sum() == 6

    # Again: nothing runs (finished and failed points are skipped); --retry-failed runs the failed ones.
    t0 = time.monotonic()
    assert main(["sweep", path, "-o", "out"]) == 0
    assert "this job ran 0:" in capsys.readouterr().out and time.monotonic() - t0 < 5
    assert main(["sweep", path, "-o", "out", "--retry-failed", "--quiet"]) == 0
    assert "this job ran 6: 0 ok, 6 failed" in capsys.readouterr().out


def _state(pid: int) -> str:
    """The process state letter of ``pid`` (T: stopped), from /proc; "" once it is gone."""
    try:
        return open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()[0]
    except OSError:
        return ""


def test_a_killed_sweep_resumes_its_point_from_the_checkpoint(here):
    """SIGKILL while the first point runs (after its first checkpoint): the sweep run again finds it
    'running', continues it from the checkpoint, runs the rest; its file equals an uninterrupted run's.

    The point stops itself at 30 l/c_r of its 50 (the hook), between its checkpoints at 20 and 40: a
    longer drive would only lengthen the resumed point, the second point and the reference run."""
    long = {"drive.duration": 50.0, "drive.v0": 0.002, "checkpoint.every": 20.0}
    text = 'base = "tiny.toml"\n[set]\n' + "".join(f'"{k}" = {v}\n' for k, v in long.items()) + \
        '[grid]\n"load.FN" = [1.0, 0.5]\n'
    path = _write(here / "long.toml", text)
    cmd = [sys.executable, "-m", "parslip", "sweep", path, "-o", "out"]
    env = cli_env()
    # The point stops itself (the hook stop_at) at 30 l/c_r of drive, past its first checkpoint at 20, and
    # is killed there: however fast the host, it cannot finish first.
    from parslip.scene.derive import derive
    from parslip.scene.load import load
    st = derive(load(str(here / "tiny.toml"), {**long, "load.FN": 1.0}))
    stop = st.n_drive_start + (st.n_steps - st.n_drive_start) * 30 // 50
    p = subprocess.Popen(cmd, cwd=here, env={**env, "PARSLIP_TEST_HOOKS": f"stop_at=0:{stop}"},
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    ckpt = here / "out" / "points" / "p000.vtkhdf.ckpt.h5"
    deadline = time.monotonic() + 120
    while _state(p.pid) != "T" and time.monotonic() < deadline and p.poll() is None:
        time.sleep(0.05)
    p.send_signal(signal.SIGKILL)
    p.wait()
    assert ckpt.exists(), p.stderr.read().decode()[-2000:]
    assert json.loads((here / "out" / "points" / "p000.json").read_text())["status"] == "running"
    r = subprocess.run(cmd, cwd=here, env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
    assert "p000: was cut short (attempt 1); continuing from its checkpoint" in r.stderr
    assert "2 points: 2 ok, 0 failed" in r.stdout
    assert not ckpt.exists()                                  # a finished point's checkpoint is removed
    ref = parslip.run("tiny.toml", out=here / "ref.vtkhdf", sets={**long, "load.FN": 1.0}, progress=False)
    got, want = datasets(here / "out" / "points" / "p000.vtkhdf")[0], datasets(ref.path)[0]
    for name in want:
        if name.startswith("interface/"):
            assert got[name].tobytes() == want[name].tobytes(), name


def test_a_point_left_running_by_a_job_the_watchdog_ended_is_failed_on_resume(here):
    """What the sweep finds after the watchdog took a job down: the point's record says running and its
    file says failed (the monitor marks it).  Resumed, the sweep marks it failed and runs the rest."""
    path = _write(here / "s.toml", 'base = "tiny.toml"\n[grid]\n"load.FN" = [1.0, 0.5]\n')
    sw = S.load_sweep(path)
    S.prepare(sw, "out")
    p0 = sw.points[0]
    S.write_record("out", p0, {"status": "running"})
    with h5py.File(S.out_path("out", p0), "w") as f:
        put_status(f, "failed: watchdog: rank 1 stopped answering at step 3000")
    todo, notes = S.triage(sw, "out")
    assert [p.name for p in todo] == ["p001"]
    assert notes == ["p000: failed: watchdog: rank 1 stopped answering at step 3000 (the job ended under it); "
                     "not run again"]
    assert S.read_record("out", p0)["status"].startswith("failed: watchdog: rank 1 stopped answering")


def test_a_hang_the_watchdog_ends_fails_its_point_and_the_resumed_sweep_runs_the_rest(here):
    """Two ranks per point; rank 1 stops (SIGSTOP, the test hook) where p000's drive starts: the watchdog
    (6 s) ends the job (exit 3) and marks p000's file failed.  The sweep run again marks p000 failed, not
    run again, and runs p001.

    The hook acts at an agreement of the ranks, and past the drive's start the ranks agree only every
    half second of work, which is the rest of this short run: the one agreement every run makes in its
    drive is at the drive's first step (the loop stops there to start the drive clock)."""
    path = _write(here / "s.toml", 'base = "tiny.toml"\nranks_per_point = 2\n[set]\n"run.watchdog" = 6.0\n'
                                   '[grid]\n"load.FN" = [1.0, 0.5]\n')
    from parslip.scene.derive import derive
    from parslip.scene.load import load
    drive_start = derive(load(str(here / "tiny.toml"), {"load.FN": 1.0})).n_drive_start
    env = {"PARSLIP_CACHE_DIR": os.environ["PARSLIP_CACHE_DIR"]}
    p = run_limited_here(here, 2, "sweep", path, "-o", "out",
                         env={**env, "PARSLIP_TEST_HOOKS": f"stop_at=1:{drive_start}"})
    assert p.returncode == 3, p.stderr[-3000:]
    assert "watchdog" in p.stderr and not (here / "out" / "summary.csv").exists()
    p0, p1 = S.load_sweep(path).points
    assert S.read_record("out", p0)["status"] == "running"
    deadline = time.monotonic() + 30                          # the file is marked once the ranks are gone
    while not str(S._file_status(S.out_path("out", p0))).startswith("failed") and time.monotonic() < deadline:
        time.sleep(0.5)
    p = run_limited_here(here, 2, "sweep", path, "-o", "out", env=env)
    assert p.returncode == 0, p.stderr[-3000:]
    assert "p000: failed: watchdog" in p.stderr and "(the job ended under it); not run again" in p.stderr
    rows = _csv(here / "out" / "summary.csv")
    assert rows[0]["status"].startswith("failed: watchdog") and "rank 1 stopped answering" in rows[0]["status"]
    assert rows[1]["status"] == "ok"


def test_a_point_killed_again_and_again_is_failed(here):
    path = _write(here / "s.toml", 'base = "tiny.toml"\n[grid]\n"load.FN" = [1.0]\n')
    sw = S.load_sweep(path)
    S.prepare(sw, "out")
    p0 = sw.points[0]
    for attempt in (1, 2):
        S.write_record("out", p0, dict(S.read_record("out", p0) or {}, status="running"))
        todo, _ = S.triage(sw, "out")
        assert todo == [p0] and S.read_record("out", p0)["unexplained"] == attempt
    S.write_record("out", p0, dict(S.read_record("out", p0), status="running"))
    todo, notes = S.triage(sw, "out")
    assert todo == [] and "interrupted 3 times" in notes[0]


def test_stop_after_stops_with_checkpoints_and_the_sweep_continues(here, capsys):
    """p000 (about 8 s here) stops at the deadline with a checkpoint, p001 does not start; run again, p000
    continues from its checkpoint (not from the start) and p001 runs.  The deadline, 1.5 s, leaves a loaded
    host time to plan before p000 starts, and p000 is long enough that a fast host does not finish it."""
    text = ('base = "tiny.toml"\n[set]\n"drive.v0" = 0.002\n[zip]\n"drive.duration" = [2000.0, 2.0]\n')
    path = _write(here / "s.toml", text)
    assert main(["sweep", path, "-o", "out", "--stop-after", "1.5"]) == 0
    cap = capsys.readouterr()
    assert "2 points: 0 ok, 0 failed, 2 pending (this job ran 1: 0 ok, 0 failed, 1 stopped)" in cap.out
    assert "continue with the same command" in cap.err
    p0, p1 = S.load_sweep(path).points
    rec = S.read_record("out", p0)
    assert rec["status"].startswith("stopped: checkpointed at step") and S.read_record("out", p1) is None
    step = int(rec["status"].split("step ")[1])
    assert main(["sweep", path, "-o", "out", "--quiet"]) == 0
    assert "2 points: 2 ok" in capsys.readouterr().out
    run = parslip.open(str(here / "out" / "points" / "p000.vtkhdf"))
    assert run.timings["steps"] < run.attrs["n_steps"] - step + 1     # the second run took only the rest


# ----------------------------------------------------------------------------------- under MPI --

def test_two_ranks_one_point_each_and_two_ranks_per_point(here):
    """4 points on 2 ranks, one point per rank: each group runs two, every file written by one rank and
    identical to the one-rank sweep's; then 2 ranks per point (a Split communicator of 2): the files
    come from 2 ranks and their interface records are the same bits."""
    body = '[set]\n"drive.v0" = 0.02\n[grid]\n"load.FN" = [0.5, 1.0, 1.5, 2.0]\n'
    one = _write(here / "one.toml", 'base = "tiny.toml"\n' + body)
    two = _write(here / "two.toml", 'base = "tiny.toml"\nranks_per_point = 2\n' + body)
    assert main(["sweep", one, "-o", "o1", "--quiet"]) == 0
    env = {"PARSLIP_CACHE_DIR": os.environ["PARSLIP_CACHE_DIR"]}
    for sweep_file, out, rpp in ((one, "o2", 1), (two, "o3", 2)):
        p = run_limited_here(here, 2, "sweep", sweep_file, "-o", out, env=env)
        assert p.returncode == 0, p.stderr[-3000:]
        assert "4 points: 4 ok" in p.stdout
        groups = {ln.split("group ")[1].split(":")[0] for ln in p.stderr.splitlines() if "sweep group" in ln}
        assert groups == ({"0", "1"} if rpp == 1 else {"0"}), p.stderr
        for k in range(4):
            f = here / out / "points" / f"p{k:03d}.vtkhdf"
            with h5py.File(f, "r") as h:
                assert int(h.attrs["n_ranks"]) == rpp and read_status(h) == "complete"
            got, want = datasets(f)[0], datasets(here / "o1" / "points" / f"p{k:03d}.vtkhdf")[0]
            for name in want:
                if name.startswith("interface/"):
                    assert got[name].tobytes() == want[name].tobytes(), (out, k, name)
        assert [r["mu_s"] for r in _csv(here / out / "summary.csv")] == [r["mu_s"] for r in _csv(here / "o1" /
                                                                                                  "summary.csv")]


def run_limited_here(cwd, n, *args, env=None):
    from helpers import cli_command, run_limited
    return run_limited(cli_command(n, *args), env=cli_env(**(env or {})), timeout=300, cwd=cwd)


# ---------------------------------------------------------------------------------------- maps --

def _table(here):
    from parslip.analysis import table
    rows = []
    for i, (mode, fn) in enumerate([(m, f) for m in ("push", "pull", "shear") for f in (0.25, 1.0, 4.0)]):
        rows.append({"point": f"p{i:03d}", "drive.mode": mode, "load.FN": fn, "status": "ok" if i != 4 else
                     "failed: x", "mu_s": 1.0 + i, "rupture_kind": "crack" if mode == "shear" else "pulse"})
    cols = table.columns(["drive.mode", "load.FN"])
    table.write_csv(str(here / "summary.csv"), cols, rows)
    table.write_netcdf(str(here / "summary.nc"), cols, rows)
    return rows


def test_map_draws_a_png_from_either_table(here, capsys):
    _table(here)
    for name in ("summary.csv", "summary.nc"):
        out = here / f"{name}.png"
        assert main(["map", name, "--x", "load.FN", "--y", "drive.mode", "--color", "mu_s", "-o", str(out)]) == 0
        assert out.stat().st_size > 10_000
    assert main(["map", "summary.csv", "--x", "load.FN", "--y", "drive.mode", "--color", "rupture_kind"]) == 0
    assert (here / "map_rupture_kind_load.FN_drive.mode.png").exists()


def test_map_axes_and_selection():
    from parslip.plot import maps
    pos, ticks, labels, scale = maps._axis([0.25, 1.0, 4.0], "auto")
    assert scale == "log" and labels == ["0.25", "1", "4"]
    assert maps._axis([1.0, 2.0], "auto")[3] == "linear"
    pos, ticks, labels, scale = maps._axis(["push", "pull", "push"], "auto")
    assert list(pos) == [0, 1, 0] and labels == ["push", "pull"]
    tab = {"point": ["a", "b", "c"], "k": [1.0, 2.0, 1.0], "m": ["x", "y", "y"], "status": ["ok"] * 3}
    assert maps.select(tab, {"k": 1}) == [0, 2] and maps.select(tab, {"k": 1, "m": "y"}) == [2]


@pytest.mark.parametrize("argv,message", [
    (["--x", "load.FN", "--y", "drive.mode", "--color", "nope"], "--color 'nope': no such column"),
    (["--x", "load.FN", "--y", "status", "--color", "mu_s", "--where", "drive.mode=push"], None),
    (["--x", "load.FN", "--y", "status", "--color", "mu_s"],
     "points p000 and p003 are both at (0.25, ok); accepted: --where KEY=VALUE to keep one (they differ in "
     "drive.mode)"),
    (["--x", "load.FN", "--y", "drive.mode", "--color", "mu_s", "--where", "drive.mode=slide"], "no row matches"),
])
def test_map_bad_input_is_one_line(here, capsys, argv, message):
    _table(here)
    code = main(["map", "summary.csv", *argv, "-o", str(here / "m.png")])
    if message is None:
        assert code == 0
        return
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err, err


def test_map_names_the_extra_when_xarray_is_missing(here, capsys, monkeypatch):
    _table(here)
    monkeypatch.setitem(sys.modules, "xarray", None)            # import xarray -> ImportError
    assert main(["map", "summary.nc", "--x", "load.FN", "--y", "drive.mode", "--color", "mu_s"]) == 2
    err = capsys.readouterr().err.strip()
    assert "pip install 'parslip[sweep]'" in err and "\n" not in err


def test_sweep_names_the_extra_when_h5netcdf_is_missing(here, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "h5netcdf", None)
    path = _write(here / "s.toml", 'base = "tiny.toml"\n')
    assert main(["sweep", path, "-o", "out"]) == 2
    err = capsys.readouterr().err.strip()
    assert "pip install 'parslip[sweep]'" in err and "\n" not in err
    assert not (here / "out").exists()
