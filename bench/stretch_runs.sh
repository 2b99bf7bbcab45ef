#!/usr/bin/env bash
# Whole-run benchmark of the paper's stretch test (issue 3): wall time, Newton and linear iterations,
# assembly vs linear-solve time and peak memory, from each run's stats.json.
# Usage: bench/stretch_runs.sh [SNH_BINARY] [OUTDIR] -- CONFIG...
#   CONFIG is element:res:solver[:refactorize], e.g. tet:10:cholmod hex:30:pcg hex:10:cholmod:refactorize
#   (default: res 10 and 20, both elements, cholmod and pcg). Prints one markdown table row per run.
set -euo pipefail
SNH="${1:-build/release/apps/snh}"
OUT="${2:-/tmp/snh-bench}"
shift 2 || true
[ "${1:-}" = "--" ] && shift
configs=("$@")
if [ ${#configs[@]} -eq 0 ]; then
  configs=(tet:10:cholmod tet:10:pcg hex:10:cholmod hex:10:pcg tet:20:cholmod tet:20:pcg hex:20:cholmod hex:20:pcg)
fi
field() { sed -n "s/^  \"$1\": \([^,]*\),\{0,1\}$/\1/p" "$2" | head -1; }
echo "| element | res | solver | threads | wall s | Newton its | factorizations | CG its | assembly s | solve s | peak MiB | max residual | converged |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for cfg in "${configs[@]}"; do
  IFS=: read -r element res solver extra <<< "$cfg"
  flags=()
  [ "$extra" = refactorize ] && flags=(--refactorize) && solver="$solver --refactorize"
  for threads in ${THREADS:-2}; do
    dir="$OUT/$element-$res-${solver// /}-$threads"
    rm -rf "$dir"; mkdir -p "$OUT"
    "$SNH" stretch --element "$element" --res "$res" --solver "${solver%% *}" "${flags[@]}" --threads "$threads" --out "$dir" > "$dir.log" 2>&1 || true
    s="$dir/stats.json"
    maxres=$(grep -o '"residual": [0-9.e+-]*' "$s" | awk '{ if ($2 > m) m = $2 } END { printf "%.1e", m }')
    printf "| %s | %s | %s | %s | %.2f | %s | %s | %s | %.2f | %.2f | %.0f | %s | %s |\n" "$element" "$res" "$solver" "$threads" \
      "$(field total_seconds "$s")" "$(field newton_iterations "$s")" "$(field factorizations "$s")" "$(field linear_iterations "$s")" \
      "$(field assembly_seconds "$s")" "$(field solve_seconds "$s")" "$(field peak_memory_mib "$s")" "$maxres" \
      "$(field all_converged "$s")"
  done
done
