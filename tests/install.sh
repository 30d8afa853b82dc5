#!/usr/bin/env bash
# Test set-up: everything `python -m pytest` needs, run before it by the
# README's test command and by CI (.ci/run).  Each step is a function of its
# own, so steps added on other branches merge without touching each other;
# every step does nothing when what it installs is already there.
set -euo pipefail
cd "$(dirname "$0")/.."

# The project with the mpich wheel and the test tools, into the running Python.
# On a shared development machine `parslip` may already be installed editable
# from another checkout: reinstalling would repoint it for everyone using that
# Python, so outside CI that case only says how to test this checkout.
install_project() {
    local where
    # Without PYTHONPATH: where the installed parslip points, not this checkout through the path.
    where=$(cd / && env -u PYTHONPATH python -c 'import os, parslip; print(os.path.dirname(os.path.dirname(os.path.realpath(parslip.__file__))))' 2>/dev/null || true)
    if [ -n "$where" ] && [ "$where" != "$(pwd -P)" ] && [ "${CI:-}" != true ]; then
        echo "tests/install.sh: parslip is installed from $where; leaving it (test this checkout with PYTHONPATH=$PWD)"
        return
    fi
    python -m pip install -e ".[mpich,test]"
}

# ---- Collective HDF5 output and the launcher check ----------------------------
# The mpio venv (mpi4py and h5py built against Debian's MPICH and parallel HDF5,
# .venv-mpio/) that tests/test_parallel.py, test_failures.py and test_launcher.py
# run the command line in, and Open MPI's mpirun, the foreign launcher that
# tests/test_launcher.py is refused by.
install_mpio() {
    bash slurm/install-parallel-hdf5.sh
    if ! command -v mpirun.openmpi >/dev/null; then
        local sudo=""
        [ "$(id -u)" = 0 ] || sudo=sudo
        $sudo apt-get update -q >/dev/null
        $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -q -o DPkg::Lock::Timeout=600 \
            --no-install-recommends openmpi-bin >/dev/null
    fi
}

install_project
install_mpio
