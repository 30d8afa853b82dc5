"""The suite's ``mpiexec`` starts one job of mpi4py's MPI, not singletons of another MPI.

Debian's paraview (for the pvpython tests) puts Open MPI's launcher in
/usr/bin; conftest puts the launcher beside this Python first on PATH.
"""
import os
import shutil
import subprocess
import sys
import sysconfig

import pytest

MPIEXEC = shutil.which("mpiexec")


@pytest.mark.skipif(MPIEXEC is None, reason="needs mpiexec")
def test_mpiexec_starts_one_job_of_mpi4py_mpi():
    beside = os.path.join(sysconfig.get_path("scripts"), "mpiexec")
    if os.access(beside, os.X_OK):
        assert os.path.samefile(MPIEXEC, beside), f"mpiexec resolves to {MPIEXEC}, not {beside}"
    # Rank 0 prints what every rank sees, in one line: two ranks' prints may interleave in the pipe.
    p = subprocess.run([MPIEXEC, "-n", "2", sys.executable, "-c",
                        "from mpi4py import MPI; c = MPI.COMM_WORLD; s = c.gather((c.Get_rank(), c.Get_size()))\n"
                        "if s is not None: print(sorted(s))"],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    # A launcher of another MPI starts two singletons: each prints [(0, 1)].
    assert p.stdout.strip() == "[(0, 2), (1, 2)]", p.stdout
