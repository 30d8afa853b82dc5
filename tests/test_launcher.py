"""A foreign launcher is refused before MPI starts: exit 2, one line naming the mpiexec to use.

The real pairings run here: Open MPI's mpirun (Debian's openmpi-bin, which
tests/install.sh installs) starting the mpich wheel's Python and the mpio
venv's; the wheel's Hydra mpiexec starting an mpi4py whose MPI is Open MPI
(mpi4py's MPI4PY_LIBMPI picks the library); and processes that did not join
one world.  The decision itself is also checked on launcher environments
that cannot be produced on one machine (srun with PMI-2 and PMIx).
"""
import os
import shutil
import subprocess
import sys

import pytest

from helpers import MPIO_MPIEXEC, MPIO_PYTHON, WHEEL_MPIEXEC, cli_env, require, small_toml, unavailable
from parslip.parallel.launcher import detect_launcher, refusal

OMPI_MPIRUN = shutil.which("mpirun.openmpi")
WHEEL_MPICH = "MPICH Version:      5.0.2\nMPICH Custom Information:\thttps://pypi.org/p/mpich/5.0.2/\n"
SITE_MPICH = "MPICH Version:\t4.1.2\nMPICH Device:\tch4:ofi\n"
OPENMPI = "Open MPI v4.1.4, package: Debian OpenMPI, ident: 4.1.4, repo rev: v4.1.4, May 26, 2022"


@pytest.fixture
def tiny(tmp_path):
    sc = tmp_path / "tiny.toml"
    sc.write_text(small_toml(**{"drive.duration": 0.5}))
    return sc


def _refused(p, out, mpiexec, n):
    """Exit 2, no traceback, no output file, and exactly one line naming `mpiexec -n n`."""
    assert p.returncode == 2, p.stdout + p.stderr
    assert "Traceback" not in p.stderr
    assert not os.path.exists(out)
    lines = [ln for ln in p.stderr.splitlines() if ln.startswith("parslip:")]
    assert len(lines) == 1, p.stderr
    assert lines[0].startswith("parslip: error: launcher: ") and f"accepted: {mpiexec} -n {n} " in lines[0], lines[0]
    return lines[0]


def _ompi(n, python, *args):
    if OMPI_MPIRUN is None:
        unavailable("no mpirun.openmpi (Debian's openmpi-bin)")
    flags = ["--allow-run-as-root", "--oversubscribe"] if os.geteuid() == 0 else ["--oversubscribe"]
    return [OMPI_MPIRUN, *flags, "-n", str(n), python, "-m", "parslip", *map(str, args)]


def test_open_mpi_mpirun_with_the_mpich_wheel_is_refused(tmp_path, tiny):
    """Unchecked, both ranks abort inside MPI_Init ("unsupported PMI version PMIx", exit 16)."""
    require("gather")
    out = tmp_path / "o.vtkhdf"
    p = subprocess.run(_ompi(2, sys.executable, "run", tiny, "--out", out), env=cli_env(), capture_output=True,
                       text=True, timeout=120)
    line = _refused(p, out, WHEEL_MPIEXEC, 2)
    assert "Open MPI's mpirun" in line and "OMPI_COMM_WORLD_SIZE=2" in line and "the mpich wheel" in line


def test_open_mpi_mpirun_with_debian_mpich_is_refused(tmp_path, tiny):
    """Unchecked, this pairing starts two one-rank runs that both write the same file."""
    require("mpio")
    out = tmp_path / "o.vtkhdf"
    p = subprocess.run(_ompi(2, MPIO_PYTHON, "run", tiny, "--out", out), env=cli_env(), capture_output=True,
                       text=True, timeout=120)
    line = _refused(p, out, MPIO_MPIEXEC, 2)
    assert "MPICH 4" in line


def test_hydra_with_open_mpi_is_refused_naming_open_mpis_mpiexec(tmp_path, tiny):
    require("gather")
    if OMPI_MPIRUN is None:
        unavailable("no Open MPI library (Debian's openmpi-bin)")
    out = tmp_path / "o.vtkhdf"
    cmd = [WHEEL_MPIEXEC, "-n", "2", sys.executable, "-m", "parslip", "run", str(tiny), "--out", str(out)]
    p = subprocess.run(cmd, env=cli_env(MPI4PY_LIBMPI="libmpi.so.40"), capture_output=True, text=True, timeout=120)
    assert p.returncode == 2, p.stderr
    line = [ln for ln in p.stderr.splitlines() if ln.startswith("parslip:")]
    assert len(line) == 1 and "MPICH's Hydra mpiexec" in line[0] and "Open MPI v4" in line[0], p.stderr
    named = line[0].split("accepted: ")[1].split(" -n 2 ")[0]
    real = os.path.basename(os.path.realpath(named))
    assert real in ("orterun", "prterun") or "openmpi" in real, named
    assert not out.exists() and "Traceback" not in p.stderr


def test_processes_that_did_not_join_one_world_are_refused(tmp_path, tiny):
    """srun without PMI wire-up starts N singletons: the launcher says 2 tasks, MPI sees 1."""
    out = tmp_path / "o.vtkhdf"
    env = cli_env(SLURM_STEP_ID="0", SLURM_PROCID="0", SLURM_STEP_NUM_TASKS="2")
    p = subprocess.run([sys.executable, "-m", "parslip", "run", str(tiny), "--out", str(out)], env=env,
                       capture_output=True, text=True, timeout=120)
    line = _refused(p, out, WHEEL_MPIEXEC, 2)
    assert "Slurm's srun started 2 processes" in line and "MPI sees 1" in line


def test_info_and_keys_never_load_mpi(tiny):
    """Even under a foreign launcher's environment: they do not touch MPI at all."""
    code = ("import sys; from parslip.cli.main import main; "
            f"assert main(['info', {str(tiny)!r}]) == 0 and main(['keys']) == 0; "
            "assert 'mpi4py.MPI' not in sys.modules, 'MPI loaded'")
    p = subprocess.run([sys.executable, "-c", code], env=cli_env(OMPI_COMM_WORLD_SIZE="2", OMPI_COMM_WORLD_RANK="0"),
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr


@pytest.mark.parametrize("env,version,refused", [
    # srun with PMI-2 or PMIx starts an mpi4py built against the site's MPI: never refused.
    ({"SLURM_STEP_ID": "0", "SLURM_PROCID": "0", "SLURM_STEP_NUM_TASKS": "4", "PMI_FD": "5", "PMI_RANK": "0"},
     SITE_MPICH, False),
    ({"SLURM_STEP_ID": "0", "SLURM_PROCID": "0", "SLURM_STEP_NUM_TASKS": "4", "PMIX_RANK": "0"}, SITE_MPICH, False),
    ({"SLURM_STEP_ID": "0", "SLURM_PROCID": "0", "SLURM_STEP_NUM_TASKS": "4", "PMIX_RANK": "0"}, OPENMPI, False),
    # The mpich wheel speaks PMI-1/PMI-2 but has no PMIx: srun --mpi=pmi2 works, --mpi=pmix aborts in MPI_Init.
    ({"SLURM_STEP_ID": "0", "SLURM_PROCID": "0", "SLURM_STEP_NUM_TASKS": "4", "PMI_FD": "5", "PMI_RANK": "0"},
     WHEEL_MPICH, False),
    ({"SLURM_STEP_ID": "0", "SLURM_PROCID": "0", "SLURM_STEP_NUM_TASKS": "4", "PMIX_RANK": "0"}, WHEEL_MPICH, True),
    # Hydra starts any MPICH (Debian's Hydra runs the wheel's MPICH and back); mpirun inside a Slurm job is still mpirun.
    ({"HYDI_CONTROL_FD": "7", "PMI_SIZE": "2", "PMI_RANK": "0"}, SITE_MPICH, False),
    ({"OMPI_COMM_WORLD_SIZE": "2", "SLURM_STEP_ID": "0", "SLURM_PROCID": "0", "PMIX_RANK": "0"}, WHEEL_MPICH, True),
    ({}, OPENMPI, False),
    # A batch script's own shell is no srun step, whatever its task count.
    ({"SLURM_STEP_ID": "4294967294", "SLURM_PROCID": "0", "SLURM_NTASKS": "8"}, WHEEL_MPICH, False),
])
def test_only_pairings_known_to_fail_are_refused(env, version, refused):
    if env.get("SLURM_STEP_ID") == "4294967294":
        assert detect_launcher(env) is None
    why = refusal(detect_launcher(env), version, "/opt/mpi/bin/mpiexec", argv=["parslip", "run", "s.toml"])
    assert (why is not None) == refused, why
    if refused and "SLURM_STEP_ID" in env and "OMPI_COMM_WORLD_SIZE" not in env:
        assert "--mpi=pmi2" in why
