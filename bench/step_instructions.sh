#!/usr/bin/env bash
# Instructions per step (valgrind callgrind): raw SUMO vs flowrun baseline on the Sugiyama ring.
# Run from the repository root: bash bench/step_instructions.sh   (needs valgrind; ~3 min)
set -euo pipefail
PY=${PY:-.venv/bin/python}
count() {  # mode steps -> instructions of the whole process
  valgrind --tool=callgrind --callgrind-out-file=/dev/null "$PY" bench/step_instructions.py "$1" "$2" 2>&1 \
    | awk '/Collected/ {gsub(",", "", $4); print $4}'
}
for mode in raw exp rec; do
  a=$(count "$mode" 300); b=$(count "$mode" 1300)
  per=$(( (b - a) / 1000 ))
  echo "$mode: $per instructions/step"
  eval "per_$mode=$per"
done
awk -v r="$per_raw" -v e="$per_exp" -v c="$per_rec" 'BEGIN {
  printf "no recording / raw SUMO = %.2f, recording / raw SUMO = %.2f (instructions)\n", e / r, c / r}'
