# Sourced by the batch scripts in slurm/ (not run on its own).
#
# Responsible for what every batch script needs alike: the Python that runs
# parslip, a numba cache every rank can read, where outputs go, and the
# arithmetic on wall-clock limits.  sbatch runs a *copy* of a batch script
# from its spool directory, so the scripts find this file through
# PARSLIP_ROOT, by default the directory sbatch was called from
# (SLURM_SUBMIT_DIR): submit from the repository's root.
#
# Environment (all optional):
#   PARSLIP_VENV      venv to activate (e.g. the one slurm/install-parallel-hdf5.sh
#                     --site builds); default: the environment sbatch was called
#                     from, which Slurm passes on (an activated venv included)
#   PARSLIP_PYTHON    the interpreter (default: python)
#   PARSLIP_OUTDIR    where outputs go (default: $SCRATCH/parslip, else ./out)
#   PARSLIP_SRUN_ARGS extra srun options, e.g. "--mpi=pmi2" for the mpich wheel
#   NUMBA_CACHE_DIR   compiled kernels (default: $SCRATCH/parslip-numba-cache,
#                     else <root>/.numba-cache)

ROOT=${PARSLIP_ROOT:-${SLURM_SUBMIT_DIR:-$PWD}}
if [ ! -f "$ROOT/slurm/env.sh" ]; then
    echo "parslip batch: $ROOT is not a parslip checkout; submit from the repository's root or set PARSLIP_ROOT" >&2
    exit 2
fi
if [ -n "${PARSLIP_VENV:-}" ]; then
    # shellcheck disable=SC1091
    source "$PARSLIP_VENV/bin/activate"
fi
PY=${PARSLIP_PYTHON:-python}
PARSLIP=("$PY" -m parslip)
read -r -a SRUN_ARGS <<< "${PARSLIP_SRUN_ARGS:-}"
SRUN=(srun ${SRUN_ARGS[@]+"${SRUN_ARGS[@]}"})
OUTDIR=${PARSLIP_OUTDIR:-${SCRATCH:+$SCRATCH/parslip}}
OUTDIR=${OUTDIR:-$ROOT/out}
mkdir -p "$OUTDIR"
# numba compiles the kernels on first use and caches them beside the sources,
# or under $HOME where those are read-only: every rank of a job would compile
# at once and race on the same files.  One shared cache, filled once by
# warm_numba_cache in the batch shell, is read by every rank of every job.
export NUMBA_CACHE_DIR=${NUMBA_CACHE_DIR:-${SCRATCH:+$SCRATCH/parslip-numba-cache}}
export NUMBA_CACHE_DIR=${NUMBA_CACHE_DIR:-$ROOT/.numba-cache}
mkdir -p "$NUMBA_CACHE_DIR"

say() { echo "parslip batch ${SLURM_JOB_ID:-?}: $*" >&2; }

# The --set options among parslip run options, into the array SETS (what
# `parslip info` and the warm-up accept).  ${SETS[@]+"${SETS[@]}"} expands an
# empty array under `set -u` on the bash 4.2 of older clusters too.
only_sets() {
    SETS=()
    while [ $# -gt 0 ]; do
        case $1 in
            --set) SETS+=(--set "${2:-}"); shift ;;
            --set=*) SETS+=("$1") ;;
        esac
        shift
    done
}

# Compile the kernels once, in this one process, on a tiny copy of SCENE (the
# kernels' types do not depend on its size).  A failure only costs the ranks
# their own compile, so it is reported and ignored.
warm_numba_cache() {
    local scene=$1; shift
    local tmp
    tmp=$(mktemp -d)
    if ! "${PARSLIP[@]}" run "$scene" "$@" --out "$tmp/warm.vtkhdf" --quiet --no-png \
            --set lattice.top_rows=3 --set lattice.top_cols=8 --set lattice.bottom_rows=3 \
            --set lattice.bottom_cols=12 --set load.ramp=0.1 --set load.settle=0.1 \
            --set drive.duration=0.1 --set output.snapshots=1 --set interface.slip_reach=0 >"$tmp/log" 2>&1; then
        say "numba warm-up failed (the ranks compile for themselves):"; tail -n 3 "$tmp/log" >&2
    fi
    rm -rf "$tmp"
}

# HH:MM:SS, MM:SS or D-HH:MM:SS (squeue's %L) -> seconds.
hms_to_s() {
    local t=$1 d=0
    case $t in *-*) d=${t%%-*}; t=${t#*-} ;; esac
    local IFS=:
    # shellcheck disable=SC2206
    local p=($t) s=0 x
    for x in "${p[@]}"; do s=$(( s * 60 + 10#$x )); done
    echo $(( d * 86400 + s ))
}
s_to_hms() { printf '%02d:%02d:%02d' $(( $1 / 3600 )) $(( $1 % 3600 / 60 )) $(( $1 % 60 )); }

# --stop-after for this job: PARSLIP_STOP_AFTER if set, else the job's time
# left minus PARSLIP_STOP_MARGIN seconds (default 600: enough to write the
# checkpoint and leave), so the run stops cleanly before the limit; the
# SIGUSR1 requested by --signal is the backstop.  Prints nothing when unknown.
stop_after() {
    if [ -n "${PARSLIP_STOP_AFTER:-}" ]; then echo "$PARSLIP_STOP_AFTER"; return; fi
    command -v squeue >/dev/null && [ -n "${SLURM_JOB_ID:-}" ] || return 0
    local left
    left=$(squeue -h -j "$SLURM_JOB_ID" -o %L 2>/dev/null) || return 0
    case $left in ""|UNLIMITED|INVALID|NOT_SET) return 0 ;; esac
    local s=$(( $(hms_to_s "$left") - ${PARSLIP_STOP_MARGIN:-600} ))
    [ $s -gt 60 ] && s_to_hms $s
    return 0
}
