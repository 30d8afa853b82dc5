"""Bad input: one line naming the key, the value and what is accepted, exit code 2.

Also: an existing output is never overwritten without --overwrite, and
`parslip info` reports the derived quantities.
"""
import os
import shutil
import subprocess
import sys

import pytest

from parslip.cli import main

MPIEXEC = shutil.which("mpiexec")


def _run(capsys, *argv):
    code = main(list(argv))
    cap = capsys.readouterr()
    return code, cap.out, cap.err


@pytest.fixture
def push(tmp_path):
    p = tmp_path / "s.toml"
    p.write_text('[drive]\nmode = "push"\nv0 = 1e-3\n')
    return str(p)


CASES = [
    # (overrides, fragments that the one error line must contain)
    (["--set", "drive.speed=1"], ["drive.speed", "unknown key", "accepted keys"]),
    (["--set", "load.FN=\"heavy\""], ["load.FN", "'heavy'", "expected a number"]),
    (["--set", "lattice.top_rows=2.5"], ["lattice.top_rows", "2.5", "expected an integer"]),
    (["--set", "interface.kx=-0.1"], ["interface.kx", "-0.1", ">= 0"]),
    (["--set", "material.bottom_kn=-5"], ["material.bottom_kn", "-5.0", "> 0"]),
    (["--set", "interface.delta_b=0.5"], ["interface.delta_b", "0.5", "delta_b > delta0"]),
    (["--set", "material.nu=0.3"], ["material.nu", "0.3", "k_t < 0", "nu <= 0.25"]),
    (["--set", "material.nu=0.3", "--set", "material.model=plane_stress"], None),   # fine in plane stress
    (["--set", "drive.v0=0"], ["drive.v0", "0.0", "> 0"]),
    (["--set", "drive.v0=-1e-3"], ["drive.v0", "-0.001", "> 0"]),
    (["--set", "time.dt=1.0"], ["time.dt", "1.0", "above the stability limit", "accepted"]),
    (["--set", "drive.mode=sideways"], ["drive.mode", "sideways", "'push'"]),
    (["--set", "novalue"], ["novalue", "key=value"]),
    (["--set", "drive.v0=.01"], None),                                   # Python spelling of a number
    (["--set", "lattice.bottom_rows=1"], ["lattice.bottom_rows", "1", "or 0 for a free block"]),
]


@pytest.mark.parametrize("extra,frags", CASES)
def test_bad_values_give_one_line_and_exit_2(capsys, push, extra, frags):
    code, out, err = _run(capsys, "info", push, *extra)
    if frags is None:
        assert code == 0, err
        return
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("parslip: error: "), err
    assert "Traceback" not in err
    for frag in frags:
        assert frag in lines[0], (frag, lines[0])


def test_missing_and_malformed_scene(capsys, tmp_path):
    code, _, err = _run(capsys, "info", str(tmp_path / "nope.toml"))
    assert code == 2 and "no such file" in err and len(err.strip().splitlines()) == 1
    bad = tmp_path / "bad.toml"
    bad.write_text("[drive\nmode = push\n")
    code, _, err = _run(capsys, "info", str(bad))
    assert code == 2 and "malformed TOML" in err and len(err.strip().splitlines()) == 1
    code, _, err = _run(capsys, "info", str(tmp_path))
    assert code == 2 and "directory" in err


def test_existing_output_is_never_overwritten(capsys, tmp_path, push):
    out = tmp_path / "r.vtkhdf"
    out.write_bytes(b"precious")
    code, _, err = _run(capsys, "run", push, "--out", str(out))
    assert code == 2 and "exists" in err and "--overwrite" in err
    assert out.read_bytes() == b"precious"


def test_info_reports_both_stability_criteria(capsys, push):
    code, out, _ = _run(capsys, "info", push)
    assert code == 0
    # velocities in c_r (the default unit): Eq. 2.2's 7/3 and 1/9 times (c_s/c_r)^2 = 1/0.910996^2
    for frag in ("k_n = 2.81154", "k_t = 0.133883", "c_r = 1 = 0.91100 c_s", "0.94750 c_s", "2/omega_max",
                 "a/c_l = 0.557869", "ranks            1 to", "MiB"):
        assert frag in out, frag


def test_keys_lists_units_and_ranges(capsys):
    code, out, _ = _run(capsys, "keys")
    assert code == 0 and "drive.v0" in out and "c_r" in out and "l/c_r" in out


@pytest.mark.skipif(MPIEXEC is None, reason="needs mpiexec")
def test_too_many_ranks_is_bad_input(tmp_path):
    sc = tmp_path / "tiny.toml"
    sc.write_text("[lattice]\ntop_rows = 3\ntop_cols = 4\nbottom_rows = 0\n"
                  "[drive]\nv0 = 0.01\nduration = 1.0\n")
    p = subprocess.run([MPIEXEC, "-n", "5", sys.executable, "-m", "parslip", "run", str(sc),
                        "--out", str(tmp_path / "o.vtkhdf")], capture_output=True, text=True, timeout=120)
    assert p.returncode == 2, p.stderr
    lines = [ln for ln in p.stderr.strip().splitlines() if ln.startswith("parslip: error")]
    assert len(lines) == 1 and "ranks = 5" in lines[0] and "accepted: 1 to 4 ranks" in lines[0], p.stderr
    assert "Traceback" not in p.stderr
    assert not os.path.exists(tmp_path / "o.vtkhdf")


def test_console_script_exit_code_without_traceback(tmp_path):
    p = subprocess.run([sys.executable, "-m", "parslip", "run", str(tmp_path / "missing.toml")],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and "Traceback" not in p.stderr
    assert p.stderr.strip().splitlines() == [f"parslip: error: scene '{tmp_path / 'missing.toml'}': no such file; "
                                             "accepted: a TOML scene such as run/push.toml"]


def test_output_held_open_elsewhere_is_bad_input(capsys, tmp_path, push):
    import h5py
    out = tmp_path / "held.vtkhdf"
    with h5py.File(out, "w"):
        pass
    with h5py.File(out, "r"):                # e.g. open in ParaView
        code, _, err = _run(capsys, "run", push, "--out", str(out), "--overwrite", "--set", "drive.duration=0.1")
    assert code == 2 and "cannot open for writing" in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1


def test_free_block_runs_and_reports_its_own_rank_limit(capsys, tmp_path, push):
    code, out, _ = _run(capsys, "info", push, "--set", "lattice.bottom_rows=0")
    assert code == 0 and "ranks            1 to 100" in out         # 100 columns, a column each at most
    code, _, err = _run(capsys, "run", push, "--out", str(tmp_path / "free.vtkhdf"), "--set", "lattice.bottom_rows=0",
                        "--set", "drive.duration=0.2", "--quiet")
    assert code == 0, err
    assert not (tmp_path / "free_spacetime.png").exists()


def test_snapshot_count_is_as_asked(tmp_path, push):
    import h5py
    for dur in (0.05, 0.5):
        out = tmp_path / f"s{dur}.vtkhdf"
        assert main(["run", push, "--out", str(out), "--quiet", "--no-png", "--set", f"drive.duration={dur}",
                     "--set", "output.snapshots=20"]) == 0
        with h5py.File(out, "r") as f:
            assert f["VTKHDF/Steps"].attrs["NSteps"] == 21
            vals = f["VTKHDF/Steps/Values"][...]
            assert vals[0] == 0.0 and vals[-1] == pytest.approx(dur, abs=0.01)


@pytest.mark.parametrize("ranks", [1, 2])
def test_a_lattice_too_big_for_the_host_is_refused_before_anything_is_allocated(tmp_path, ranks):
    """10^9 nodes: every rank predicts its own peak (scene.memory) against its host's MemAvailable and the
    ranks agree, so the job ends with one line and exit 2 instead of being killed by the kernel hours into
    set-up.  The need it names is at least the state and index alone: 2 Verlet levels of x, y in float64
    (32 B) + the owned-node index (64 B) + the bond cells (48 B) per node, over the ranks."""
    import re

    from helpers import cli_command, cli_env
    sc = tmp_path / "huge.toml"
    sc.write_text("[lattice]\ntop_rows = 10000\ntop_cols = 100000\nbottom_rows = 20\nbottom_cols = 300000\n"
                  "[drive]\nmode = \"push\"\nv0 = 1e-3\nduration = 0.001\n"
                  "[output]\nsnapshots = 0\nfields = \"interface\"\n")
    out = tmp_path / "o.vtkhdf"
    p = subprocess.run(cli_command(ranks, "run", sc, "--out", out, "--no-png"), env=cli_env(), capture_output=True,
                       text=True, timeout=180)
    assert p.returncode == 2, p.stdout + p.stderr
    lines = [ln for ln in p.stderr.splitlines() if ln.startswith("parslip: error")]
    assert len(lines) == 1 and "Traceback" not in p.stderr, p.stderr
    m = re.search(r"1,006,000,000 nodes on (\d) rank\(s\): rank \d would need about ([\d.]+) GiB but its host has "
                  r"([\d.]+) GiB available; accepted:", lines[0])
    assert m and int(m.group(1)) == ranks, lines[0]
    assert float(m.group(2)) >= 1.006e9 * (32 + 64 + 48) / ranks / 2**30 > float(m.group(3)), lines[0]
    assert not out.exists()


def test_info_says_when_a_lattice_is_too_big_for_this_host(capsys, tmp_path):
    sc = tmp_path / "huge.toml"
    sc.write_text("[lattice]\ntop_rows = 10000\ntop_cols = 100000\nbottom_rows = 20\nbottom_cols = 300000\n"
                  "[output]\nsnapshots = 0\nfields = \"interface\"\n")
    code, out, _ = _run(capsys, "info", str(sc))
    line = next(ln for ln in out.splitlines() if ln.startswith("memory"))
    assert code == 0 and "this host has available: `parslip run` refuses it here" in line, line
    code, out, _ = _run(capsys, "info", str(tmp_path.joinpath("small.toml").write_text("") or tmp_path / "small.toml"))
    line = next(ln for ln in out.splitlines() if ln.startswith("memory"))
    assert code == 0 and "refuses" not in line, line
