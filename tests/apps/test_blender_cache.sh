#!/usr/bin/env bash
# A flesh run's PC2 point caches, loaded by Debian's Blender in background mode into its Mesh Cache modifier,
# play the run's OBJ frames (blender_pc2.py). Skipped (77) where Blender is not installed; CI installs it.
# Usage: test_blender_cache.sh SNH_BINARY TEST_DATA_DIR
set -euo pipefail
snh=$1
data=$2
here=$(cd "$(dirname "$0")" && pwd)
if ! command -v blender > /dev/null; then
  echo "blender is not installed: skipped"
  exit 77
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$snh" flesh "$data/flesh/limb.gltf" --resolution 12 --out "$work/limb" --no-report > "$work/run.log" 2>&1 \
  || { cat "$work/run.log"; exit 1; }
# Blender 3.4 prints its banner and may warn about audio or the GPU in a container: only its exit code and our lines count.
if ! blender --background --factory-startup --python-exit-code 1 --python "$here/blender_pc2.py" -- "$work/limb" \
     > "$work/blender.log" 2>&1; then
  cat "$work/blender.log"
  exit 1
fi
grep -E "pc2:" "$work/blender.log"
echo "blender_cache: ok"
