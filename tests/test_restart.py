"""Checkpoints and restarts: a continued run is the uninterrupted run, bit for bit, on any rank count.

Also: a process killed while it writes a checkpoint leaves the previous one
whole, a restart appends to the output without losing or repeating frames,
a finished run can be extended (drive.duration is safe to change), and bad
checkpoints are refused with one line and exit 2.
"""
import os

import h5py
import numpy as np
import pytest

from helpers import assert_extension_is_the_run, datasets, reference_run, run_cli
from parslip.io.contract import read_status

# SMALL with a checkpoint every 1 l/c_r (about 300 steps).
CKPT = {"checkpoint.every": 1.0, "output.snapshots": 4}


def _assert_same(got, ref, skip=()):
    assert got.keys() == ref.keys()
    for name in ref:
        if name in skip:
            continue
        assert got[name].shape == ref[name].shape and got[name].tobytes() == ref[name].tobytes(), name


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    """The reference: SMALL with checkpoints, run to the end on one rank without a stop."""
    sc, out = reference_run(tmp_path_factory.mktemp("ref"), CKPT)
    return sc, datasets(out)


@pytest.mark.parametrize("n_first,n_then", [(1, 1), (2, 3)])
def test_killed_mid_checkpoint_then_restarted_is_bitwise_the_uninterrupted_run(tmp_path, uninterrupted, n_first,
                                                                            n_then):
    """Rank 0 dies (SIGKILL) halfway through writing its second checkpoint; the first stays whole;
    the restart, on the same or another rank count, appends to the output file and ends with
    exactly the uninterrupted run's datasets."""
    sc, (ref, ref_attrs) = uninterrupted
    out = tmp_path / "o.vtkhdf"
    ckpt = str(out) + ".ckpt.h5"
    p = run_cli(n_first, "run", sc, "--out", out, "--no-png", "--quiet", env={"PARSLIP_TEST_HOOKS": "kill_in_checkpoint=2"})
    assert p.returncode != 0
    assert os.path.exists(ckpt + ".tmp")                    # the killed write, left half-done
    with h5py.File(ckpt, "r") as f:                         # the previous checkpoint, whole
        assert f.attrs["complete"] == 1
        step = int(f.attrs["step"])
    with h5py.File(out, "r") as f:
        assert read_status(f) == "running"               # killed: nobody closed it
    p = run_cli(n_then, "run", sc, "--out", out, "--no-png", "--quiet", "--restart", ckpt)
    assert p.returncode == 0, p.stderr
    got, attrs = datasets(out)
    assert attrs["status"] == "complete" and attrs["n_ranks"] == n_then and step > 0
    _assert_same(got, ref)


def test_a_finished_run_extended_is_the_longer_run(tmp_path, uninterrupted):
    """drive.duration may change on a restart: 3 l/c_r, then continued to 6, equals 6 at once
    (the interface record; snapshot times depend on the duration)."""
    sc, (ref, _) = uninterrupted
    assert_extension_is_the_run(sc, tmp_path / "o.vtkhdf", ref, 3.0, 2, 1)


def test_stop_after_writes_a_checkpoint_and_says_how_to_continue(tmp_path, uninterrupted):
    """--stop-after 0: the run stops at its first chance, checkpoints, exits 0 and prints the command
    that continues; that command finishes the run."""
    sc, (ref, _) = uninterrupted
    out = tmp_path / "o.vtkhdf"
    p = run_cli(2, "run", sc, "--out", out, "--no-png", "--stop-after", "0")
    assert p.returncode == 0, p.stderr
    assert "checkpointed at step" in p.stderr and f"--restart {out}.ckpt.h5" in p.stderr
    with h5py.File(out, "r") as f:
        assert read_status(f).startswith("checkpointed at step")
    p = run_cli(2, "run", sc, "--out", out, "--no-png", "--quiet", "--restart", "auto")
    assert p.returncode == 0, p.stderr
    _assert_same(datasets(out)[0], ref)
    p = run_cli(1, "run", sc, "--out", out, "--no-png", "--restart", "auto")      # complete: nothing to do
    assert p.returncode == 0 and "nothing to do" in p.stderr


def test_restart_auto_without_a_checkpoint_starts_the_run(tmp_path, uninterrupted):
    sc, (ref, _) = uninterrupted
    out = tmp_path / "o.vtkhdf"
    p = run_cli(1, "run", sc, "--out", out, "--no-png", "--quiet", "--restart", "auto")
    assert p.returncode == 0, p.stderr
    _assert_same(datasets(out)[0], ref)


def _one_error_line(p):
    lines = [ln for ln in p.stderr.strip().splitlines() if ln.startswith("parslip: error")]
    assert p.returncode == 2 and len(lines) == 1 and "Traceback" not in p.stderr, p.stderr
    return lines[0]


def test_bad_checkpoints_are_refused_with_one_line(tmp_path, uninterrupted):
    sc, _ = uninterrupted
    out = tmp_path / "o.vtkhdf"
    p = run_cli(1, "run", sc, "--out", out, "--no-png", "--quiet", "--set", "drive.duration=1.0")
    assert p.returncode == 0, p.stderr
    ckpt = str(out) + ".ckpt.h5"
    # Another scene: a different drive speed is not safe to change.
    line = _one_error_line(run_cli(1, "run", sc, "--out", out, "--restart", ckpt, "--set", "drive.v0=0.03"))
    assert "drive.v0 = 0.03" in line and "0.02" in line and "accepted: the same scene" in line
    # Not a checkpoint at all.
    line = _one_error_line(run_cli(1, "run", sc, "--out", out, "--restart", out))
    assert "not a parslip checkpoint" in line
    # An incomplete checkpoint (the writer stopped before setting `complete`).
    bad = tmp_path / "bad.ckpt.h5"
    with h5py.File(ckpt, "r") as f, h5py.File(bad, "w") as g:
        for k, v in f.attrs.items():
            g.attrs[k] = v
        g.attrs["complete"] = 0
    line = _one_error_line(run_cli(1, "run", sc, "--out", out, "--restart", bad))
    assert "incomplete checkpoint" in line
    # A checkpoint whose output file is gone.
    line = _one_error_line(run_cli(1, "run", sc, "--out", tmp_path / "gone.vtkhdf", "--restart", ckpt))
    assert "no such file" in line
    # A malformed --stop-after.
    line = _one_error_line(run_cli(1, "run", sc, "--out", tmp_path / "x.vtkhdf", "--stop-after", "soon"))
    assert "--stop-after 'soon'" in line and "HH:MM:SS" in line


def test_checkpoint_holds_the_state_by_global_id(tmp_path, uninterrupted):
    """The checkpoint's arrays are the run's state: u at the checkpoint's step equals the output's
    interface displacements at the frame of that step (both in a, the frame's in l)."""
    sc, _ = uninterrupted
    out = tmp_path / "o.vtkhdf"
    # a frame every step, so one falls on the checkpoint's step whatever the cadence's ratio to dt
    p = run_cli(2, "run", sc, "--out", out, "--no-png", "--quiet", "--set", "drive.duration=2.0",
                "--set", "output.interface_dt=1e-9")
    assert p.returncode == 0, p.stderr
    with h5py.File(str(out) + ".ckpt.h5", "r") as c, h5py.File(out, "r") as f:
        step, u = int(c.attrs["step"]), c["u"][...]
        assert c.attrs["n_ranks"] == 2 and u.shape == (f.attrs["n_nodes"], 2)
        assert step == f.attrs["n_steps"]
        g = f["interface"]
        k = int(g.attrs["frames_written"]) - 1
        l = float(f.attrs["l"])
        # The block's interface nodes: global ids of row 0 of the top block, column by column.
        pts = f["VTKHDF/Points"][-int(f.attrs["n_nodes"]):]
        y0 = pts[:, 1].reshape(-1)
        top_row = np.isclose(y0 - u[:, 1], (4 - 1) * np.sqrt(3) / 2 + 0.5)
        np.testing.assert_array_equal(u[top_row, 0] * (1.0 / l), g["ux"][k])     # frames store u x (1/l)


ADDED_EVENT_FIELDS = ("energy", "traction", "dissipated")      # /interface/events fields since format 3 began


def test_a_checkpoint_written_by_an_earlier_version_still_restarts(tmp_path):
    """tests/data/checkpoint_059d7ae: SMALL with healing (heal_time 0.3, so the candidate and clock rows
    hold state), run to 3 l/c_r on 1 rank by the code at 059d7ae (format "parslip checkpoint 3", omega_max
    rounded to 24 bits, so every x86-64 host derives its dt), its output file and its last checkpoint kept.
    Its scene is stripped of the keys added since checkpoints were first written (``checkpoint.IMPLIED``),
    and its output file of the event fields added since (ADDED_EVENT_FIELDS), as an older version wrote
    them: each key counts as the behaviour it implies, each field is NaN for the events before.  Continued
    to 6 l/c_r on 2 ranks by today's code, its /interface is bitwise today's uninterrupted run."""
    import gzip
    import shutil
    from pathlib import Path

    import h5py

    from parslip.io.checkpoint import IMPLIED
    from parslip.io.scenefile import loads, to_toml
    data = Path(__file__).parent / "data" / "checkpoint_059d7ae"
    sc = data / "scene.toml"
    out = tmp_path / "old.vtkhdf"
    for name, dest in (("run.vtkhdf.gz", out), ("run.vtkhdf.ckpt.h5.gz", tmp_path / "old.vtkhdf.ckpt.h5")):
        with gzip.open(data / name, "rb") as src, open(dest, "wb") as dst:
            shutil.copyfileobj(src, dst)
    with h5py.File(str(out) + ".ckpt.h5", "r+") as f:
        saved = loads(str(f.attrs["scene"]))
        assert all(saved.get(key, value) == value for key, value in IMPLIED.items())
        f.attrs["scene"] = to_toml({k: v for k, v in saved.items() if k not in IMPLIED})
        old = int(f.attrs["events_written"])
    with h5py.File(out, "r+") as f:                     # events recorded before they had an energy and a traction
        for name in ADDED_EVENT_FIELDS:
            if name in f["interface/events"]:
                del f["interface/events"][name]
    p = run_cli(1, "run", sc, "--out", out, "--no-png", "--quiet", "--set", "interface.contact=1.0",
                "--restart", str(out) + ".ckpt.h5")         # a key added since: written with its old behaviour
    assert p.returncode == 2 and "interface.contact = 1.0 but the checkpoint was written with 0.0" in p.stderr
    p = run_cli(2, "run", sc, "--out", out, "--no-png", "--quiet", "--set", "drive.duration=6.0",
                "--restart", str(out) + ".ckpt.h5")
    assert p.returncode == 0, p.stderr
    ref = tmp_path / "now.vtkhdf"
    p = run_cli(1, "run", sc, "--out", ref, "--no-png", "--quiet", "--set", "drive.duration=6.0")
    assert p.returncode == 0, p.stderr
    got, attrs = datasets(out)
    want, _ = datasets(ref)
    assert attrs["status"] == "complete"
    names = [n for n in want if n.startswith("interface/")]
    assert "interface/events/kind" in names and len(want["interface/time"]) > 100
    assert old > 0
    for name in names:
        if name.split("/")[-1] in ADDED_EVENT_FIELDS and name.startswith("interface/events/"):
            assert np.isnan(got[name][:old]).all(), name          # not known: NaN, never a made-up value
            assert got[name][old:].tobytes() == want[name][old:].tobytes(), name
            continue
        assert got[name].tobytes() == want[name].tobytes(), name
