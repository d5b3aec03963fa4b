#!/usr/bin/env bash
# Instructions per step (valgrind callgrind): raw SUMO vs flowrun baseline on the Sugiyama ring.
# Run from the repository root: bash bench/step_instructions.sh   (needs valgrind; ~4 min)
# The 2,200-car ring instead: SCALE=100 STEPS="60 160" MODES="raw exp" bash bench/step_instructions.sh
# (~10 min)
# Flow's merge0 (open network), per env step of two sims, and its SUMO-alone floor:
#   MODES="merge_raw merge" STEPS="300 600" bash bench/step_instructions.sh
# Flow's grid0 and its floor: MODES="grid_raw grid" STEPS="300 600" bash bench/step_instructions.sh
# Flow's figureeight0 and SUMO alone replaying its commands:
#   MODES="eight_raw eight" STEPS="300 1300" bash bench/step_instructions.sh
# An ARS worker of figureeight0 playing one candidate (env, policy, observation statistics):
#   MODES="eight_ars" STEPS="300 1300" bash bench/step_instructions.sh
#
# Each mode runs twice (500 and 2,500 steps); the difference / 2,000 is the cost of one step,
# start-up cancelled out. The count is repeatable to the instruction only with: one BLAS
# thread (OpenBLAS's idle threads spin and are counted), a fixed hash seed, and no address
# randomisation (setarch -R) -- so all three are set here.
set -euo pipefail
PY=${PY:-.venv/bin/python}
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 PYTHONHASHSEED=0
NORAND=(setarch "$(uname -m)" -R)
"${NORAND[@]}" true 2>/dev/null || NORAND=()
SCALE=${SCALE:-1}
read -r SHORT LONG <<< "${STEPS:-500 2500}"
count() {  # mode steps -> instructions of the whole process
  "${NORAND[@]}" valgrind --tool=callgrind --callgrind-out-file=/dev/null "$PY" bench/step_instructions.py "$1" "$2" "$SCALE" 2>&1 \
    | awk '/Collected/ {gsub(",", "", $4); print $4}'
}
"$PY" bench/step_instructions.py raw 10  # compile every module once, outside the counts
case " ${MODES:-} " in *" grid_raw "*)  # SUMO alone replays the env's commands: log them
  "$PY" bench/grid_steps.py record grid0 "$LONG" ;; esac
case " ${MODES:-} " in *" eight_raw "*)
  "$PY" bench/step_instructions.py eight_record "$LONG" ;; esac
per_raw=0 per_exp=0 per_rec=0 per_merge_raw=0 per_merge=0 per_grid_raw=0 per_grid=0
per_eight_raw=0 per_eight=0
for mode in ${MODES:-raw exp rec}; do  # raw exp rec merge_raw merge grid_raw grid eight_raw eight eight_ars
  a=$(count "$mode" "$SHORT"); b=$(count "$mode" "$LONG")
  per=$(( (b - a) / (LONG - SHORT) ))
  echo "$mode: $per instructions/step"
  eval "per_$mode=$per"
done
awk -v r="$per_raw" -v e="$per_exp" -v c="$per_rec" -v mr="$per_merge_raw" -v m="$per_merge" \
  -v gr="$per_grid_raw" -v g="$per_grid" -v er="$per_eight_raw" -v ee="$per_eight" \
  'BEGIN { if (r > 0) {
  if (e > 0) printf "no recording / raw SUMO = %.2f (instructions)\n", e / r
  if (c > 0) printf "recording / raw SUMO = %.2f (instructions)\n", c / r }
  if (mr > 0 && m > 0) printf "merge / merge SUMO alone = %.2f (instructions)\n", m / mr
  if (gr > 0 && g > 0) printf "grid0 / grid0 SUMO alone = %.2f (instructions)\n", g / gr
  if (er > 0 && ee > 0) printf "figureeight0 / SUMO alone = %.2f (instructions)\n", ee / er }'
