#!/usr/bin/env bash
# Regenerates the tables and figures of numbers under docs/, one command per page, from the checkout
# it sits in.  Run it from a clean checkout (git status shows nothing): every row and picture records
# the commit it ran at (plot.provenance), and tests/test_shipped_numbers.py checks that each was
# computed under today's defaults.  Regenerate a page whenever a default it depends on changes.
#
#   bash postprocess/docs_numbers.sh accuracy   # docs/studies/accuracy_{push,shear}.csv and Pareto plots (~5 min)
#   bash postprocess/docs_numbers.sh friction   # docs/studies/friction_*.csv, img/map_*, img/friction_* (~3 min, 2 ranks)
#   bash postprocess/docs_numbers.sh paper      # docs/studies/img/ figures of the paper page (~6 min)
#   bash postprocess/docs_numbers.sh scaling    # docs/hpc/shear_l500_*.png and the l = 500 run's numbers (~4 min, 2 ranks)
#   bash postprocess/docs_numbers.sh interfaces # docs/studies/interfaces_*.csv and img/interfaces_* (~4 min, 2 ranks)
#   bash postprocess/docs_numbers.sh cracks_energy      # docs/studies/cracks_energy.csv and img/cracks_energy_*
#   bash postprocess/docs_numbers.sh cracks_precursors  # docs/studies/cracks_precursors.csv and img/cracks_precursors_*
#   bash postprocess/docs_numbers.sh cracks_supershear  # docs/studies/cracks_supershear.csv and img/cracks_supershear_*
#   bash postprocess/docs_numbers.sh cracks_healing     # docs/studies/cracks_healing.csv and img/cracks_healing_*
#     (docs/studies/cracks.md: each runs its sweeps run/studies/cracks_<study>*.toml, then postprocess/cracks.py)
#   bash postprocess/docs_numbers.sh weakening_cohesive_zone  # docs/studies/weakening_cohesive_zone.csv and
#     img/weakening_cohesive_zone_* (docs/studies/weakening.md: its sweeps run/studies/weakening_cohesive_zone*.toml,
#     then postprocess/weakening_cohesive_zone.py)
#   bash postprocess/docs_numbers.sh weakening_andrews  # docs/studies/weakening_andrews.csv, weakening_kammer.csv,
#                                                       # img/weakening_andrews_* and img/weakening_kammer_*
#   bash postprocess/docs_numbers.sh weakening_kammer   # the same: Kammer's speeds are measured on Andrews' runs
#     (docs/studies/weakening.md: the sweeps run/studies/weakening_andrews*.toml, then postprocess/weakening.py
#     andrews and kammer; one command makes both tables: 10 min on 2 ranks, 33 min when the machine is loaded)
#   bash postprocess/docs_numbers.sh weakening_shape    # docs/studies/weakening_shape.csv and img/weakening_shape_*
#     (docs/studies/weakening.md, study 2: the sweeps run/studies/weakening_shape*.toml, then postprocess/weakening.py
#     shape; 9 runs: 14 min on 2 ranks while the machine was loaded, 4 min of CPU)
#   bash postprocess/docs_numbers.sh weakening_precursors  # docs/studies/weakening_precursors.csv,
#     weakening_precursors_arrests.csv and img/weakening_precursors_* (study 5: the sweeps
#     run/studies/weakening_precursors*.toml, then postprocess/weakening.py precursors: 7.4 min of CPU, 31 min
#     of wall time on 2 cores loaded by other jobs)
#
# OUT (default out/docs) keeps the runs; DOCS (default docs) is where the tables and figures go: point it
# outside the checkout to keep the checkout clean while several pages run, and copy them in afterwards.
# NP (default 2) is the rank count of the parallel runs.  The numbers the pages quote are printed (or
# left in OUT) for the page to be rewritten from.
set -euo pipefail
cd "$(dirname "$0")/.."
what=${1:?"usage: $0 accuracy|friction|paper|scaling|interfaces|cracks_energy|cracks_precursors|cracks_supershear|cracks_healing|weakening_andrews|weakening_kammer|weakening_cohesive_zone|weakening_shape|weakening_precursors"}
OUT=${OUT:-out/docs}
DOCS=${DOCS:-docs}
NP=${NP:-2}
PY=${PYTHON:-python}
# the checkout's own package, not the one installed (a script under postprocess/ would import the installed one)
export PYTHONPATH="$PWD${PYTHONPATH:+:$PYTHONPATH}"
MPIEXEC=${MPIEXEC:-mpiexec}
mkdir -p "$OUT" "$DOCS/studies/img" "$DOCS/hpc"
case "$what" in
accuracy)
    for s in push shear; do
        "$PY" -m parslip accuracy "run/$s.toml" -o "$OUT/acc_$s" --repeat 2
        cp "$OUT/acc_$s/accuracy.csv" "$DOCS/studies/accuracy_$s.csv"
        cp "$OUT/acc_$s/accuracy_pareto.png" "$DOCS/studies/accuracy_pareto_$s.png"
        cat "$OUT/acc_$s/accuracy.md"
    done ;;
friction)
    for s in loading rate stiffness_push stiffness_shear; do
        "$MPIEXEC" -n "$NP" "$PY" -m parslip sweep "run/studies/friction_$s.toml" -o "$OUT/friction/$s"
    done
    "$PY" postprocess/friction_study.py --dir "$OUT/friction" -o "$DOCS/studies/img" --tables "$DOCS/studies" ;;
paper)
    "$PY" -m parslip paper -o "$OUT/paper"
    f="$OUT/paper/figures"
    for pair in push/spacetime:push_spacetime pull/spacetime:pull_spacetime shear/spacetime:shear_spacetime \
                push/front_speed:push_front_speed shear/front_speed:shear_front_speed \
                push/pulse_width:push_pulse_width push/slip_records:push_slip_records \
                shear_l500/spacetime:shear_l500_spacetime v0_sweep:v0_sweep push_vs_pull:push_vs_pull; do
        cp "$f/${pair%%:*}.png" "$DOCS/studies/img/${pair##*:}.png"
    done
    # Fig. 7a's sigma_xy map with the first T0 front's tip halfway (the middle of its three maps, t = 67 l/c_r)
    cp "$(ls "$f"/shear/map_sxy_t*.png | sort | sed -n 2p)" "$DOCS"/studies/img/shear_map_sxy_t67.png
    cat "$OUT/paper/claims.md" ;;
scaling)
    "$MPIEXEC" -n "$NP" "$PY" -m parslip run run/shear_l500.toml --out "$OUT/shear_l500.vtkhdf" --overwrite --no-png
    "$PY" -m parslip figures "$OUT/shear_l500.vtkhdf" -o "$OUT/shear_l500_figures" --only spacetime
    cp "$OUT/shear_l500_figures/spacetime.png" "$DOCS"/hpc/shear_l500_spacetime.png
    for t in 30 50; do
        "$PY" -m parslip render "$OUT/shear_l500.vtkhdf" --field sxy --time $t -o "$DOCS/hpc/shear_l500_sxy_t$t.png"
    done
    "$PY" -m parslip fronts "$OUT/shear_l500.vtkhdf" ;;
interfaces)
    for s in precursors barriers supershear damping heal_time heal_speed; do
        "$MPIEXEC" -n "$NP" "$PY" -m parslip sweep "run/studies/interface_$s.toml" -o "$OUT/interfaces/interface_$s"
    done
    "$PY" postprocess/interface_studies.py --dir "$OUT/interfaces" -o "$DOCS/studies/img" --tables "$DOCS/studies" ;;
cracks_energy|cracks_precursors|cracks_supershear|cracks_healing)
    study=${what#cracks_}
    for f in run/studies/cracks_"$study"*.toml; do
        "$MPIEXEC" -n "$NP" "$PY" -m parslip sweep "$f" -o "$OUT/cracks/$(basename "$f" .toml)"
    done
    "$PY" postprocess/cracks.py "$study" --dir "$OUT/cracks" -o "$DOCS/studies/img" --tables "$DOCS/studies" ;;
weakening_cohesive_zone)
    for f in run/studies/weakening_cohesive_zone*.toml; do
        "$MPIEXEC" -n "$NP" "$PY" -m parslip sweep "$f" -o "$OUT/weakening/$(basename "$f" .toml)"
    done
    "$PY" postprocess/weakening_cohesive_zone.py --dir "$OUT/weakening" -o "$DOCS/studies/img" --tables "$DOCS/studies" ;;
weakening_andrews|weakening_kammer)
    for f in run/studies/weakening_andrews*.toml; do
        "$MPIEXEC" -n "$NP" "$PY" -m parslip sweep "$f" -o "$OUT/weakening/$(basename "$f" .toml)"
    done
    for study in andrews kammer; do
        "$PY" postprocess/weakening.py "$study" --dir "$OUT/weakening" -o "$DOCS/studies/img" --tables "$DOCS/studies"
    done ;;
weakening_shape)
    for f in run/studies/weakening_shape*.toml; do
        "$MPIEXEC" -n "$NP" "$PY" -m parslip sweep "$f" -o "$OUT/weakening/$(basename "$f" .toml)"
    done
    "$PY" postprocess/weakening.py shape --dir "$OUT/weakening" -o "$DOCS/studies/img" --tables "$DOCS/studies" ;;
weakening_precursors)
    for f in run/studies/weakening_precursors*.toml; do
        "$MPIEXEC" -n "$NP" "$PY" -m parslip sweep "$f" -o "$OUT/weakening/$(basename "$f" .toml)"
    done
    "$PY" postprocess/weakening.py precursors --dir "$OUT/weakening" -o "$DOCS/studies/img" --tables "$DOCS/studies" ;;
*)
    echo "docs_numbers.sh: $what: accepted: accuracy, friction, paper, scaling, interfaces, cracks_energy, cracks_precursors, cracks_supershear, cracks_healing, weakening_andrews, weakening_kammer, weakening_cohesive_zone, weakening_shape, weakening_precursors" >&2; exit 2 ;;
esac
