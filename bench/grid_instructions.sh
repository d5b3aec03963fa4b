#!/usr/bin/env bash
# Instructions per step (valgrind callgrind) of Flow's grid0 and grid1: the env against SUMO
# alone on the same traffic (load-proof, unlike bench/env_vs_sumo.py's CPU time): SUMO alone replays
# the signal states and car modes the env set (logged by a first env run, not counted).
# Run from the repository root: bash bench/grid_instructions.sh   (needs valgrind; ~10 min)
# GRIDS="grid0" STEPS="300 600" bash bench/grid_instructions.sh
# Each count runs twice (SHORT and LONG steps); the difference per step cancels start-up.
# One BLAS thread, a fixed hash seed and no address randomisation keep counts repeatable.
set -euo pipefail
PY=${PY:-.venv/bin/python}
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 PYTHONHASHSEED=0
NORAND=(setarch "$(uname -m)" -R)
"${NORAND[@]}" true 2>/dev/null || NORAND=()
read -r SHORT LONG <<< "${STEPS:-300 600}"
count() {  # mode grid steps -> instructions of the whole process
  "${NORAND[@]}" valgrind --tool=callgrind --callgrind-out-file=/dev/null "$PY" bench/grid_steps.py "$1" "$2" "$3" 2>&1 \
    | awk '/Collected/ {gsub(",", "", $4); print $4}'
}
for grid in ${GRIDS:-grid0 grid1}; do
  "$PY" bench/grid_steps.py record "$grid" "$LONG"  # also compiles every module, uncounted
  for mode in raw env; do
    a=$(count "$mode" "$grid" "$SHORT"); b=$(count "$mode" "$grid" "$LONG")
    eval "per_$mode=$(( (b - a) / (LONG - SHORT) ))"
  done
  awk -v g="$grid" -v r="$per_raw" -v e="$per_env" \
    'BEGIN { printf "%s: env %d, SUMO alone %d instructions/step: ratio %.2f\n", g, e, r, e / r }'
done
