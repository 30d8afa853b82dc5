#!/bin/bash
# Submits a restart chain: N links of slurm/chain.sbatch, each depending on
# the one before (afterok), all running SCENE into the same OUT.  Each link
# continues from the checkpoint the previous one wrote before its time limit,
# so a run longer than the queue's limit finishes across N jobs.
#
#   bash slurm/submit-chain.sh SCENE OUT [N] [parslip run options...]
#   bash slurm/submit-chain.sh run/push.toml $SCRATCH/push.vtkhdf 6 --set drive.duration=2000
#
# N (default 4) is an upper bound: once OUT is complete, the remaining links
# start, find it complete and exit 0 at once.  afterok, not afterany: a link
# that failed (exit != 0) leaves nothing sound to continue from, and the rest
# of the chain is then dropped by Slurm instead of repeating the failure.
# sbatch options for every link go in PARSLIP_SBATCH_ARGS (e.g.
# "--ntasks=32 --time=12:00:00").  Prints the job ids, first to last.
set -euo pipefail
usage="usage: bash slurm/submit-chain.sh SCENE OUT [N] [parslip run options...]"
SCENE=${1:?$usage}
OUT=${2:?$usage}
shift 2
N=4
if [ $# -gt 0 ] && [[ $1 =~ ^[0-9]+$ ]]; then N=$1; shift; fi
if [ "$N" -lt 1 ]; then echo "submit-chain: N = $N; accepted: a number of links >= 1" >&2; exit 2; fi
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
export PARSLIP_ROOT=${PARSLIP_ROOT:-$(dirname "$here")}   # the links find slurm/env.sh from any submit directory
read -r -a EXTRA <<< "${PARSLIP_SBATCH_ARGS:-}"
prev=""
for ((k = 1; k <= N; k++)); do
    dep=()
    [ -n "$prev" ] && dep=(--dependency="afterok:$prev")
    prev=$(sbatch --parsable ${EXTRA[@]+"${EXTRA[@]}"} ${dep[@]+"${dep[@]}"} "$here/chain.sbatch" "$SCENE" "$OUT" "$@")
    prev=${prev%%;*}          # --parsable prints "jobid[;cluster]"
    echo "$prev"
done
