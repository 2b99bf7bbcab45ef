#!/usr/bin/env bash
# Characters nobody here made (docs/results.md "Characters nobody here made"): every rigged, animated character
# of Debian's assimp-testmodels, read directly (through assimp) and as glTF converted by assimp's own exporter,
# and a character made in Debian's Blender (tests/apps/blender_character.py) as its glTF and FBX exporters
# write it; each run by `snh flesh MODEL` with no other option. Prints one Markdown row per run.
# Usage: bench/characters.sh [BUILD_DIR] [WORK_DIR]   (defaults build/release and a temporary directory)
set -uo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$here/build/release}"
work="${2:-$(mktemp -d)}"
snh="$build/apps/snh"
models=/usr/share/assimp/models
[ -x "$snh" ] || { echo "characters: $snh is not built" >&2; exit 2; }
[ -d "$models" ] || { echo "characters: assimp-testmodels is not installed (scripts/install-deps)" >&2; exit 2; }
mkdir -p "$work"

inputs=()
for m in FBX/huesitos.fbx FBX/animation_with_skeleton.fbx X/Testwuson.X X/BCN_Epileptic.X X/anim_test.x; do
  inputs+=("$models/$m")
  gltf="$work/$(basename "${m%.*}").gltf"
  if assimp export "$models/$m" "$gltf" -f gltf2 > "$work/export.log" 2>&1; then inputs+=("$gltf")
  else echo "characters: assimp export $m failed: $(tail -1 "$work/export.log")" >&2; fi
done
if command -v blender > /dev/null; then
  blender -b --factory-startup --python-exit-code 1 -P "$here/tests/apps/blender_character.py" -- "$work/blender" > "$work/blender.log" 2>&1 \
    && inputs+=("$work/blender/character.glb" "$work/blender/character.fbx")
fi

echo "| character | read as | joints | triangles | meshes | open edges | lattice (chosen) | frames converged | Newton / frame | smallest skin volume, flesh / LBS | exit | time |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
for input in "${inputs[@]}"; do
  name="$(basename "$input")"
  out="$work/run-$name"
  start=$(date +%s.%N)
  "$snh" flesh "$input" --out "$out" --no-report --force > "$work/$name.log" 2>&1
  code=$?
  seconds=$(echo "$(date +%s.%N) - $start" | bc)
  python3 - "$out/stats.json" "$input" "$code" "$seconds" <<'EOF'
import json, os, sys
path, model, code, seconds = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4])
name = os.path.basename(model)
if not os.path.exists(path):
    print(f"| {name} | | | | | | | not run | | | {code} | {seconds:.1f} s |")
    sys.exit()
s = json.load(open(path))
frames = [f for f in s["frames"] if f["frame"] > 0]
converged = sum(1 for f in frames if f["converged"])
last = s["frames"][-1]
total = round(s["end_time"] * last["frame"] / last["time"]) if last["frame"] > 0 else 0  # the clip's frames
newton = sum(f["newton_iterations"] for f in frames) / max(1, len(frames))
flesh = min((f["surface_volume_ratio"] for f in frames), default=1.0)
lbs = min((f["lbs_volume_ratio"] for f in frames), default=1.0)
read = s.get("model_format", "")
print(f"| {name} | {read} | {s['joints']} | {s['model_triangles']} | {len(s['parts'])} | {s['open_edges']} | "
      f"{s['resolution']} ({s['cells']} cells) | {converged} of {total} | {newton:.1f} | {flesh:.3f} / {lbs:.3f} | {code} | {seconds:.1f} s |")
EOF
done
