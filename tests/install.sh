#!/usr/bin/env bash
# Installs what the test suite needs; the README's test command runs it before pytest:
#
#     bash tests/install.sh && python -m pytest -n 2 --dist loadfile
#
# Each part is one function, idempotent and quiet when there is nothing to do.
set -euo pipefail
cd "$(dirname "$0")/.."

# --- Python: the package with its [mpich,test,viz,docs,sweep] extras ----------------------------
install_python() {
    # An editable install that already exists (on a shared machine: another checkout's) is left
    # pointing where it points, and only the dependencies are installed: the suite imports this
    # checkout anyway, as pytest runs from its root (or through PYTHONPATH).  Otherwise this
    # checkout is installed editable, as on a fresh machine.
    if python -m pip show parslip 2>/dev/null | grep -q "^Editable project location:"; then
        local reqs
        reqs=$(mktemp)
        python - <<'EOF' > "$reqs"
try:
    import tomllib
except ImportError:                     # Python 3.10
    import tomli as tomllib
p = tomllib.load(open("pyproject.toml", "rb"))["project"]
reqs = list(p["dependencies"])
for extra in ("mpich", "test", "viz", "docs", "sweep"):
    reqs += p["optional-dependencies"][extra]
print("\n".join(reqs))
EOF
        PIP_ROOT_USER_ACTION=ignore python -m pip install -q --disable-pip-version-check -r "$reqs"
        rm -f "$reqs"
    else
        PIP_ROOT_USER_ACTION=ignore python -m pip install -q --disable-pip-version-check -e ".[mpich,test,viz,docs,sweep]"
    fi
}

# --- ParaView: the real client the sidecar tests open files with (tests/test_xdmf.py) -----------
# Debian 12's ParaView 5.11: pvpython is in python3-paraview.  Recommends are skipped (docs, and
# mpi-default-bin; Open MPI comes anyway through python3-mpi4py, and tests/conftest.py keeps the
# suite's mpiexec on mpi4py's MPI).  Without apt-get the pvpython tests skip and say why.
# apt_provide COMMAND HINT PACKAGE...: Debian's PACKAGEs, unless COMMAND is on the PATH already; without
# apt-get, HINT is said and the tests that need COMMAND skip and say why.
apt_provide() {
    local cmd=$1 hint=$2
    shift 2
    if command -v "$cmd" >/dev/null 2>&1; then
        return 0
    fi
    if ! command -v apt-get >/dev/null 2>&1; then
        echo "tests/install.sh: no apt-get here; $hint" >&2
        return 0
    fi
    local sudo=""
    if [ "$(id -u)" -ne 0 ]; then
        sudo="sudo -n"
    fi
    export DEBIAN_FRONTEND=noninteractive
    $sudo apt-get update -qq
    # Another apt-get may hold the lock on a shared machine: wait for it rather than fail.
    $sudo apt-get install -y -qq -o DPkg::Lock::Timeout=900 --no-install-recommends "$@" >/dev/null
    command -v "$cmd" >/dev/null
}

install_paraview() {
    apt_provide pvpython "install ParaView >= 5.11 with pvpython, or its tests skip" paraview python3-paraview
}

# --- Collective HDF5 output and the launcher check -------------------------------------------------
# The mpio venv (mpi4py and h5py built against Debian's MPICH and parallel HDF5, .venv-mpio/) that
# tests/test_parallel.py, test_failures.py and test_launcher.py run the command line in, and Open MPI's
# mpirun, the foreign launcher that tests/test_launcher.py is refused by.
install_mpio() {
    bash slurm/install-parallel-hdf5.sh
    if ! command -v mpirun.openmpi >/dev/null; then
        local sudo=""
        [ "$(id -u)" = 0 ] || sudo=sudo
        $sudo apt-get update -q >/dev/null
        $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -q -o DPkg::Lock::Timeout=900 \
            --no-install-recommends openmpi-bin >/dev/null
    fi
}

# --- The docs site's MathJax 3 and the browser its test reads the site with --------------------------
# MathJax: the npm package, pinned in docs/gen_ref.py (MATHJAX_VERSION), into .cache/mathjax (git ignores
# it); the docs build copies it into the site (the hook installs it itself when it is missing).  Chromium:
# Debian's, for tests/test_site.py, which opens the built pages from disk with no network; without apt-get
# that test skips and says why.
install_mathjax() {
    local version
    version=$(sed -n 's/^MATHJAX_VERSION = "\(.*\)"$/\1/p' docs/gen_ref.py)
    if [ -f .cache/mathjax/node_modules/mathjax/package.json ] \
        && grep -q "\"version\": \"$version\"" .cache/mathjax/node_modules/mathjax/package.json; then
        return 0
    fi
    if ! command -v npm >/dev/null 2>&1; then
        echo "tests/install.sh: no npm here; install Node.js and npm, or the docs build cannot vendor MathJax" >&2
        return 0
    fi
    mkdir -p .cache/mathjax
    npm install --prefix .cache/mathjax --no-save --no-audit --no-fund --loglevel=error "mathjax@$version" >/dev/null
}

install_chromium() {
    apt_provide chromium "install Chromium (chromium on PATH), or tests/test_site.py skips" chromium
}

install_python
install_paraview
install_mpio
install_mathjax
install_chromium
