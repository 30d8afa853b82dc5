"""A job never spins silently: the watchdog, signals while a rank is blocked, progress while ranks wait,
and writes that fail.

Faults come from the one test hook (``parslip.hooks``): ``stop_at`` makes a rank stop itself with a real
SIGSTOP, ``block_at`` keeps a rank out of the collective the others wait in (it still answers
heartbeats), ``write_error_at_frame`` makes a write fail with ENOSPC.  A real full disk is a tmpfs
mounted for the test.  Every run has a hard time limit (``helpers.run_limited``).
"""
import os
import signal
import subprocess
import time

import h5py
import pytest

from helpers import WRITERS, cli_command, cli_env, ranks_below, require, run_cli, small_toml
from parslip.io.contract import read_status

from conftest import LONG
HOOKS = "PARSLIP_TEST_HOOKS"
# Where the hooks strike: inside the drive (LONG on SMALL ramps and settles for 781 steps), and no later:
# the ranks step up to it oversubscribed, the collective writer's (Debian's MPICH) polling without yielding.
STEP = 1000


def _status(out, wait_s=10.0) -> str:
    """The file's status, waiting up to ``wait_s`` for one other than "running" (the collective writer's
    file is marked by a process that starts once the job is gone) and for the file to open at all (an
    aborted rank may still hold its lock for a moment after the launcher returned)."""
    deadline = time.monotonic() + wait_s
    while True:
        try:
            with h5py.File(out, "r") as f:
                s = read_status(f)
                assert int(f["interface"].attrs["frames_written"]) >= 0
        except OSError:
            s = "unreadable"
        if s not in ("running", "unreadable") or time.monotonic() >= deadline:
            return s
        time.sleep(0.5)



@pytest.mark.parametrize("writer", WRITERS)
def test_watchdog_names_the_rank_that_stopped(tmp_path, long_scene, writer):
    """Rank 1 of 3 stops (SIGSTOP) in the drive: after the watchdog's 8 s every rank that can speak logs
    its step and phase, one line names rank 1, the job ends with exit 3 and the file says failed."""
    require(writer)
    out = tmp_path / "o.vtkhdf"
    t0 = time.monotonic()
    p = run_cli(3, "run", long_scene, "--out", out, "--no-png", "--quiet", "--watchdog", "8", writer=writer,
                env={HOOKS: f"stop_at=1:{STEP}"}, timeout=120)
    took = time.monotonic() - t0
    assert p.returncode == 3, p.stderr[-3000:]
    assert "watchdog report: rank 0 is at step" in p.stderr and "watchdog report: rank 2 is at step" in p.stderr
    line = [ln for ln in p.stderr.splitlines() if "run failed: watchdog" in ln]
    assert len(line) == 1 and "rank 1 stopped answering" in line[0], p.stderr[-3000:]
    assert "Traceback" not in p.stderr
    assert took < 60, took
    status = _status(out, wait_s=30)
    assert status.startswith("failed: watchdog") and "rank 1 stopped answering" in status, status


def test_watchdog_says_where_ranks_wait_when_none_is_silent(tmp_path, long_scene):
    """Rank 1 never reaches the agreement the others wait in, but its monitor still answers: the line
    says no rank is silent and where each waits."""
    require("gather")
    out = tmp_path / "o.vtkhdf"
    p = run_cli(2, "run", long_scene, "--out", out, "--no-png", "--set", "output.progress_s=1", "--watchdog", "8",
                env={HOOKS: f"block_at=1:{STEP}"}, timeout=120)
    assert p.returncode == 3, p.stderr[-3000:]
    assert "no rank is silent, but they wait in different places" in p.stderr
    assert _status(out).startswith("failed: watchdog")
    # Rank 0's progress lines go on while it waits (the monitor thread speaks, not the blocked loop).
    stamps = [ln for ln in p.stderr.splitlines() if "parslip 0/2 INFO: step " in ln]
    assert len(stamps) >= 5, p.stderr[-3000:]


def test_sigterm_while_a_rank_is_stopped_ends_the_job_within_seconds(tmp_path, long_scene):
    """SIGTERM to the launcher while rank 1 is stopped: no checkpoint can be written (it needs every
    rank), so the others end the job within seconds with one clear line, exit 3; not a spin until SIGKILL."""
    require("gather")
    out = tmp_path / "o.vtkhdf"
    cmd = cli_command(3, "run", long_scene, "--out", out, "--no-png", "--quiet", "--watchdog", "600")
    proc = subprocess.Popen(cmd, env=cli_env(**{HOOKS: f"stop_at=1:{STEP}"}), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        deadline = time.monotonic() + 90
        while not _stopped_rank(proc.pid):
            assert time.monotonic() < deadline and proc.poll() is None, "rank 1 never stopped"
            time.sleep(0.2)
        time.sleep(1.0)
        t0 = time.monotonic()
        os.kill(proc.pid, signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
        took = time.monotonic() - t0
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode == 3, err[-3000:]
    assert took < 15, took
    assert "SIGTERM arrived while rank" in err and "none was written" in err, err[-3000:]
    assert _status(out, wait_s=20).startswith("failed: SIGTERM")


def _stopped_rank(launcher_pid) -> bool:
    """A rank below the launcher in state T (stopped)."""
    for pid in ranks_below(launcher_pid):
        try:
            with open(f"/proc/{pid}/stat") as f:
                if f.read().rsplit(")", 1)[1].split()[0] == "T":
                    return True
        except OSError:
            pass
    return False


@pytest.mark.parametrize("writer", WRITERS)
def test_a_failed_write_ends_every_rank_with_one_line(tmp_path, long_scene, writer):
    """A write that fails (ENOSPC, injected at frame 200) on rank 0: every rank ends with exit 3, one line
    naming the file, the frames that are safe and the checkpoint to continue from; status failed."""
    require(writer)
    out = tmp_path / "o.vtkhdf"
    p = run_cli(2, "run", long_scene, "--out", out, "--no-png", "--quiet", "--set", "checkpoint.every=2",
                writer=writer, env={HOOKS: "write_error_at_frame=200"}, timeout=120)
    assert p.returncode == 3, p.stderr[-3000:]
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert "Traceback" not in p.stderr and "No space left on device" in p.stderr
    failed = [ln for ln in lines if ln.startswith("parslip: run failed:")]
    assert len(failed) == 1, p.stderr
    assert str(out) in failed[0] and "frames 0 to" in failed[0] and f"{out}.ckpt.h5" in failed[0], failed[0]
    status = _status(out)
    assert status.startswith("failed: cannot write"), status
    with h5py.File(out, "r") as f:
        assert 0 < int(f["interface"].attrs["frames_written"]) <= 200


@pytest.fixture
def tiny_disk(tmp_path):
    """A 2 MiB tmpfs (needs root); skipped where mounting is not allowed."""
    d = tmp_path / "disk"
    d.mkdir()
    if os.geteuid() != 0 or subprocess.run(["mount", "-t", "tmpfs", "-o", "size=2m", "tmpfs", str(d)],
                                           capture_output=True).returncode != 0:
        pytest.skip("cannot mount a tmpfs here (needs root)")
    yield d
    subprocess.run(["umount", "-l", str(d)], capture_output=True)


def _held_run(cmd, hook: str, held, act, timeout: float = 90):
    """Start ``cmd`` with the test hook ``hook``, wait until the run holds (it creates ``held``), do ``act(proc)``,
    then wait for the job's end under a hard limit (a hang kills the whole process group and fails).  Returns
    (exit code, stderr)."""
    proc = subprocess.Popen(cmd, env=cli_env(**{HOOKS: hook}), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while not held.exists():
            assert time.monotonic() < deadline and proc.poll() is None, proc.stderr.read() if proc.poll() else ""
            time.sleep(0.05)
        act(proc)
        _, err = proc.communicate(timeout=timeout)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    return proc.returncode, err


def test_a_real_full_disk_mid_run(tmp_path, long_scene, tiny_disk):
    """The disk fills up while the run writes (another file takes the rest of it): one line, exit 3,
    no traceback, no crash.  The run is held by the test hook at frame 32 until the disk is full, so the
    test does not race the run on a fast host.  Afterwards the file's status says the run failed and why
    (the line's reason), and the file reads back the frames it says it holds (parslip.open and parslip
    fronts), or says in one line why it cannot."""
    require("gather")
    out = tiny_disk / "o.vtkhdf"
    scene = tmp_path / "s.toml"
    scene.write_text(small_toml(**{**LONG, "drive.duration": 60.0, "output.buffer_frames": 16,
                                   "output.snapshots": 0}))
    cmd = cli_command(2, "run", scene, "--out", out, "--no-png", "--set", "output.progress_s=0.2")

    def fill_the_disk(proc):
        fd = os.open(tiny_disk / "filler", os.O_WRONLY | os.O_CREAT)     # take every block that is left
        try:
            while True:
                os.write(fd, b"\0" * 4096)
        except OSError:
            pass
        finally:
            os.close(fd)
        (tiny_disk / "o.vtkhdf.held").unlink()                          # let the run go on
    code, err = _held_run(cmd, "hold_at_frame=32", tiny_disk / "o.vtkhdf.held", fill_the_disk)
    assert code == 3, err[-3000:]
    assert "Traceback" not in err and "Segmentation" not in err, err[-3000:]
    failed = [ln for ln in err.splitlines() if ln.startswith("parslip: run failed:")]
    assert len(failed) == 1 and "No space left on device" in failed[0], err[-3000:]
    (tiny_disk / "filler").unlink()
    status = _status(out)
    assert status.startswith(f"failed: cannot write {out}") and "No space left on device" in status, status
    assert status[len("failed: "):] in failed[0], (status, failed[0])       # the reason the line gives
    _reads_back_what_it_says(out, failed[0])


def _reads_back_what_it_says(out, line):
    """A file left by a failed write: the frames its error line names are the frames parslip.open reads
    back (and parslip fronts catalogues), or both say in one line why the file cannot be read."""
    import re
    import parslip
    m = re.search(r"frames 0 to (\d+) of the interface record", line)
    try:
        run = parslip.open(out)
    except parslip.ConfigError as e:
        assert "\n" not in str(e) and str(out) in str(e), str(e)
        p = run_cli(1, "fronts", out, timeout=120)
        assert p.returncode == 2 and "Traceback" not in p.stderr, p.stderr[-2000:]
        return
    with h5py.File(out, "r") as f:
        in_file = int(f["interface"].attrs["frames_written"])
    assert len(run.times) == in_file, (len(run.times), in_file)
    assert in_file >= (int(m.group(1)) + 1 if m else 0), (in_file, line)   # at least what the line names
    p = run_cli(1, "fronts", out, timeout=120)
    one_line = len([ln for ln in p.stderr.splitlines() if ln.startswith("parslip:")]) == 1
    assert (p.returncode == 0 or (p.returncode == 2 and one_line)) and "Traceback" not in p.stderr, p.stderr


def test_an_output_that_cannot_fit_is_refused_at_once(tmp_path, tiny_disk):
    """The output is allocated whole when it is made: a 2 MiB disk refuses a run that writes more."""
    require("gather")
    scene = tmp_path / "s.toml"
    scene.write_text(small_toml(**{"drive.duration": 300.0}))
    p = run_cli(1, "run", scene, "--out", tiny_disk / "o.vtkhdf", "--no-png", "--quiet", timeout=120)
    assert p.returncode == 2, p.stderr
    assert "MiB free" in p.stderr and "accepted:" in p.stderr and "Traceback" not in p.stderr


def test_sigterm_while_the_picture_is_drawn_exits_0(tmp_path):
    """The batch system's SIGTERM comes after the drive, while rank 0 draws the picture (held there by the
    test hook): the run is complete, so the job exits 0 with a line saying what was skipped, not 15."""
    out = tmp_path / "o.vtkhdf"
    scene = tmp_path / "s.toml"
    scene.write_text(small_toml(**{"drive.duration": 2.0}))
    code, err = _held_run(cli_command(2, "run", scene, "--out", out), "hold_before_picture=1",
                          tmp_path / "o_spacetime.png.held",
                          lambda proc: os.killpg(proc.pid, signal.SIGTERM))   # as Slurm does: every process
    assert code == 0, err[-3000:]
    lines = [ln for ln in err.splitlines() if ln.startswith("parslip:")]
    assert len(lines) == 1 and "SIGTERM came after the run was complete" in lines[0], err[-3000:]
    assert _status(out) == "complete"
    assert not (tmp_path / "o_spacetime.png").exists()
