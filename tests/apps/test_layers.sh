#!/usr/bin/env bash
# Every file of a layer includes only headers of its own layer and of the layers below it (docs/design.md):
#   math <- material <- fem <- solve <- sim <- run <- setup, report on run, mesh beside material (knows math),
#   io, rig, embed and contact beside fem (know mesh and math), fem above contact (its contact terms); sim is
#   the stepping core (no files), run a run's files, setup the scene files, flesh, stretch and lab. One line per include that breaks an arrow, and a non-zero exit code.
# Usage: test_layers.sh SRC_SNH_DIR
set -u
SRC="$1"
declare -A allowed=(
  [math]="math"
  [material]="math material"
  [mesh]="math mesh"
  [io]="math mesh io"
  [rig]="math mesh rig"
  [embed]="math mesh embed"
  [contact]="math mesh contact"
  [fem]="math material mesh contact fem"
  [solve]="math material mesh contact fem solve"
  [sim]="math material mesh contact fem solve sim"
  [run]="math material mesh io contact fem solve sim run"
  [setup]="math material mesh io rig embed contact fem solve sim run setup"
  [report]="math material mesh io contact fem solve sim run report"
)
bad=0 files=0
for layer in "${!allowed[@]}"; do
  while IFS= read -r file; do
    files=$((files + 1))
    while IFS= read -r used; do
      case " ${allowed[$layer]} " in
        *" $used "*) ;;
        *) echo "FAIL: ${file#"$SRC"/} ($layer) includes snh/$used/: $layer may use only ${allowed[$layer]}"; bad=$((bad + 1)) ;;
      esac
    done < <(sed -n 's|^#include "snh/\([a-z]*\)/.*|\1|p' "$file")
  done < <(find "$SRC/$layer" -name '*.hpp' -o -name '*.cpp')
done
unknown=$(find "$SRC" -mindepth 1 -maxdepth 1 -type d -printf '%f\n' | while read -r d; do [ -n "${allowed[$d]:-}" ] || echo "$d"; done)
[ -z "$unknown" ] || { echo "FAIL: layers without arrows here: $unknown"; bad=$((bad + 1)); }
echo "$files files checked, $bad includes against the layering"
[ "$bad" -eq 0 ] && [ "$files" -gt 50 ]
