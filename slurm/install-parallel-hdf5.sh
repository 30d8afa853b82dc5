#!/usr/bin/env bash
# Builds the virtual environment in which parslip writes its output through
# HDF5's collective `mpio` driver: mpi4py and h5py compiled from source against
# one MPI and one parallel HDF5, beside the project's other dependencies.
#
# Responsible for:
#   - the MPI and the parallel HDF5 (Debian/Ubuntu: apt-get installs MPICH and
#     libhdf5-mpich-dev; on a cluster: whatever `module load` provides),
#   - a venv of its own (default .venv-mpio/ at the repository root) that never
#     holds the `mpich` wheel, so a process there loads exactly one MPI library,
#   - mpi4py and h5py built in that venv against them, the other dependencies
#     from PyPI, and parslip itself (editable, unless --no-project),
#   - doing nothing when the venv already works (h5py.get_config().mpi and an
#     MPI of the expected family), so a second run costs a second.
#
# Usage:
#   bash slurm/install-parallel-hdf5.sh                  # Debian/Ubuntu, apt + .venv-mpio/
#   bash slurm/install-parallel-hdf5.sh --site           # cluster: after `module load ...`
#   bash slurm/install-parallel-hdf5.sh --venv DIR --no-project
#
# On a cluster (no apt; the site's MPI and parallel HDF5 come from modules):
#   module load openmpi hdf5/parallel        # names are site-specific
#   MPICC=mpicc HDF5_DIR=$HDF5_ROOT bash slurm/install-parallel-hdf5.sh --site
#   source .venv-mpio/bin/activate && srun parslip run run/push.toml
# HDF5_DIR must hold include/hdf5.h and lib/libhdf5.so of an HDF5 built with
# --enable-parallel; the script takes HDF5_DIR, else HDF5_ROOT, HDF5_HOME or
# HDF5_PREFIX (what modules commonly set), else asks `h5pcc -showconfig`.
#
# Environment (all optional):
#   PARSLIP_MPIO_VENV   the venv's directory (default: <repo>/.venv-mpio)
#   PYTHON              the interpreter the venv is made from (default: python3)
#   MPICC               MPI compiler wrapper (Debian default: mpicc.mpich, since
#                       /usr/bin/mpicc may point at Open MPI; --site default: mpicc)
#   HDF5_DIR            parallel HDF5 prefix (Debian default: the mpich flavour)
#   MPI4PY_VERSION, H5PY_VERSION   versions built (pinned for reproducible files)
#   PARSLIP_WHEEL_CACHE where built wheels are kept, keyed by compiler wrapper,
#                       HDF5, Python and version (default: ~/.cache/parslip/mpio-wheels);
#                       a new venv on the same machine then takes seconds.
#
# Exit codes: 0 the venv works (built now or already); 1 a step failed (the
# message says which); 2 a bad argument.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
VENV=${PARSLIP_MPIO_VENV:-$ROOT/.venv-mpio}
PYTHON=${PYTHON:-python3}
MPI4PY_VERSION=${MPI4PY_VERSION:-4.1.2}
H5PY_VERSION=${H5PY_VERSION:-3.16.0}
WHEEL_CACHE=${PARSLIP_WHEEL_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/parslip/mpio-wheels}
# -O1 -g0: the generated C of mpi4py and h5py is large; -O2 -g roughly doubles
# compile time and memory for no measurable gain in an I/O layer.
BUILD_CFLAGS=${CFLAGS:--O1 -g0}
SITE=0
PROJECT=1
APT_PACKAGES=(mpich libmpich-dev libhdf5-mpich-dev)

say() { echo "install-parallel-hdf5: $*" >&2; }
die() { say "error: $*"; exit 1; }

while [ $# -gt 0 ]; do
    case $1 in
        --site) SITE=1 ;;
        --no-project) PROJECT=0 ;;
        --venv) [ $# -ge 2 ] || { say "error: --venv needs a directory"; exit 2; }; VENV=$2; shift ;;
        -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
        *) say "error: unknown argument '$1'; accepted: --site, --no-project, --venv DIR, --help"; exit 2 ;;
    esac
    shift
done
case $VENV in /*) ;; *) VENV=$PWD/$VENV ;; esac
VPY=$VENV/bin/python

# The MPI family the venv must load: Debian's MPICH here; on a cluster, the
# site's (whatever mpi4py was built against is then right by construction).
if [ $SITE = 1 ]; then EXPECT_MPI=""; else EXPECT_MPI="MPICH"; fi

venv_works() {
    [ -x "$VPY" ] || return 1
    EXPECT_MPI=$EXPECT_MPI PROJECT=$PROJECT "$VPY" - <<'EOF' 2>/dev/null
import os, sys
import h5py, mpi4py
mpi4py.rc.initialize = False          # asking the library's name needs no MPI_Init
from mpi4py import MPI
import numba, numpy, scipy, matplotlib, tomli_w   # noqa: F401  the project's other dependencies
assert h5py.get_config().mpi, "h5py without MPI"
lib = MPI.Get_library_version()
assert os.environ["EXPECT_MPI"] in lib, lib
assert "pypi.org/p/mpich" not in lib, "the mpich wheel is in this venv"
if os.environ["PROJECT"] == "1":
    import parslip  # noqa: F401
EOF
}

# One build per venv at a time: a second run waits here, then finds the venv working.
mkdir -p "$WHEEL_CACHE"
if command -v flock >/dev/null; then
    exec 9>"$WHEEL_CACHE/.lock-$(printf '%s' "$VENV" | sha256sum | cut -c1-12)"
    flock 9
fi

if venv_works; then
    say "$VENV already works (h5py with MPI, $("$VPY" -c 'import h5py; print("h5py", h5py.__version__, "on HDF5", h5py.version.hdf5_version)')); nothing to do"
    exit 0
fi

T0=$(date +%s)

# ---------------------------------------------------------------- MPI, HDF5 --
if [ $SITE = 0 ]; then
    command -v dpkg-query >/dev/null || die "no dpkg: not Debian/Ubuntu; load the site's MPI and parallel HDF5 modules and run with --site"
    missing=()
    for p in "${APT_PACKAGES[@]}"; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
    done
    if [ ${#missing[@]} -gt 0 ]; then
        SUDO=""; [ "$(id -u)" = 0 ] || SUDO=sudo
        say "apt-get install ${missing[*]}"
        # The lock timeout lets this wait for another apt run (a parallel set-up step) instead of failing.
        $SUDO apt-get update -q >/dev/null
        $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -q -o DPkg::Lock::Timeout=600 \
            --no-install-recommends "${missing[@]}" >/dev/null || die "apt-get install ${missing[*]} failed"
    fi
    # Explicitly MPICH's wrapper: with Open MPI installed too (ParaView pulls it in),
    # /usr/bin/mpicc is Open MPI's, and mixing the two is what this venv exists to avoid.
    MPICC=${MPICC:-mpicc.mpich}
    HDF5_DIR=${HDF5_DIR:-/usr/lib/$(gcc -print-multiarch 2>/dev/null || echo x86_64-linux-gnu)/hdf5/mpich}
else
    MPICC=${MPICC:-mpicc}
    HDF5_DIR=${HDF5_DIR:-${HDF5_ROOT:-${HDF5_HOME:-${HDF5_PREFIX:-}}}}
    if [ -z "$HDF5_DIR" ] && command -v h5pcc >/dev/null; then
        HDF5_DIR=$(h5pcc -showconfig | sed -n 's/^ *Installation point: *//p')
    fi
    [ -n "$HDF5_DIR" ] || die "--site: set HDF5_DIR to the parallel HDF5's prefix (after module load)"
fi
command -v "$MPICC" >/dev/null || die "MPI compiler wrapper '$MPICC' not found (set MPICC)"
[ -f "$HDF5_DIR/include/hdf5.h" ] || die "HDF5_DIR=$HDF5_DIR has no include/hdf5.h"
grep -qs "Parallel HDF5: *yes" "$HDF5_DIR"/lib*/libhdf5.settings "$HDF5_DIR"/libhdf5.settings \
    || grep -qs "define H5_HAVE_PARALLEL 1" "$HDF5_DIR/include/H5pubconf.h" \
    || die "HDF5_DIR=$HDF5_DIR is a serial HDF5; accepted: one built with --enable-parallel"
say "MPI: $MPICC ($("$MPICC" -show | cut -d' ' -f1-4) ...), HDF5: $HDF5_DIR"

# --------------------------------------------------------------------- venv --
if [ ! -x "$VPY" ]; then
    say "creating $VENV from $(command -v "$PYTHON")"
    "$PYTHON" -m venv "$VENV" || die "$PYTHON -m venv $VENV failed"
fi
pip() { "$VPY" -m pip --disable-pip-version-check -q "$@"; }
if "$VPY" -m pip show -q mpich 2>/dev/null; then
    say "removing the mpich wheel from $VENV (two MPI libraries in one process break)"
    pip uninstall -y mpich
fi
# Build tools into the venv itself: pip's isolated build environments each
# fetch and unpack numpy and Cython again, which ran this machine out of memory.
pip install "setuptools>=68" wheel "Cython>=3" "numpy>=2" pkgconfig || die "pip install of the build tools failed"

# ----------------------------------------------------- mpi4py and h5py wheels --
key=$(printf '%s\n' "$("$MPICC" -show)" "$HDF5_DIR" "$("$VPY" -c 'import sys, numpy; print(sys.version, numpy.__version__.split(".")[0])')" \
      "$BUILD_CFLAGS" "$MPI4PY_VERSION" "$H5PY_VERSION" | sha256sum | cut -c1-16)
WHEELS=$WHEEL_CACHE/$key
mkdir -p "$WHEELS"
build_wheel() {  # name version env...: build once per key, with pip's own cache off so no wheel built for another MPI slips in
    local name=$1 version=$2; shift 2
    if ls "$WHEELS/$name-$version-"*.whl >/dev/null 2>&1; then
        say "$name $version: cached wheel in $WHEELS"
        return
    fi
    say "building $name $version from source (1.5 to 2 minutes on 2 cores)"
    local t=$(date +%s)
    env "$@" CFLAGS="$BUILD_CFLAGS" "$VPY" -m pip --disable-pip-version-check -q wheel --no-deps \
        --no-build-isolation --no-cache-dir --no-binary="$name" -w "$WHEELS" "$name==$version" \
        || die "building $name $version against $MPICC / $HDF5_DIR failed"
    say "$name built in $(( $(date +%s) - t )) s"
}
build_wheel mpi4py "$MPI4PY_VERSION" MPICC="$MPICC" CC="$MPICC"
pip install --no-deps --force-reinstall "$WHEELS"/mpi4py-"$MPI4PY_VERSION"-*.whl
build_wheel h5py "$H5PY_VERSION" CC="$MPICC" HDF5_MPI=ON HDF5_DIR="$HDF5_DIR"   # compiles against the mpi4py above
pip install --no-deps --force-reinstall "$WHEELS"/h5py-"$H5PY_VERSION"-*.whl

# ------------------------------------------------- the project's dependencies --
# Read from pyproject.toml so this list never drifts; mpi4py and h5py are the
# ones just built, and the `mpich` extra is never installed here.
mapfile -t deps < <("$VPY" - "$ROOT/pyproject.toml" <<'EOF'
import re, sys
try:
    import tomllib
except ImportError:            # Python 3.10
    import tomli as tomllib
with open(sys.argv[1], "rb") as f:
    deps = tomllib.load(f)["project"]["dependencies"]
for d in deps:
    if re.split(r"[\s<>=!~;\[]", d, maxsplit=1)[0].lower() not in ("mpi4py", "h5py", "mpich"):
        print(d)
EOF
)
pip install "${deps[@]}" || die "pip install of the dependencies failed"
if [ $PROJECT = 1 ]; then
    pip install --no-deps --no-build-isolation -e "$ROOT" || die "pip install -e $ROOT into $VENV failed"
fi

# ------------------------------------------------------------------- verify --
venv_works || die "the new venv does not pass its own check (h5py.get_config().mpi, MPI family '$EXPECT_MPI')"
# One collective write on two ranks, through the launcher that belongs to this MPI.
if [ $SITE = 0 ]; then
    MPIEXEC=mpiexec.mpich
    probe=$(mktemp -d)
    timeout 120 "$MPIEXEC" -n 2 "$VPY" -c "
import sys, h5py
from mpi4py import MPI
c = MPI.COMM_WORLD
with h5py.File(sys.argv[1], 'w', driver='mpio', comm=c) as f:
    d = f.create_dataset('x', (c.size,), 'i8')
    d[c.rank] = c.rank
if c.rank == 0:
    assert list(h5py.File(sys.argv[1], 'r')['x'][:]) == [0, 1]
" "$probe/probe.h5" || die "a 2-rank collective write with $MPIEXEC failed"
    rm -rf "$probe"
fi
say "ready in $(( $(date +%s) - T0 )) s: $VENV ($("$VPY" -c 'import h5py, mpi4py; print("mpi4py", mpi4py.__version__, "+ h5py", h5py.__version__, "on HDF5", h5py.version.hdf5_version, "with MPI")'))"
[ $SITE = 0 ] && say "run with: $MPIEXEC -n 2 $VPY -m parslip run run/push.toml"
exit 0
