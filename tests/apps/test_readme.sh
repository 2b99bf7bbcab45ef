#!/usr/bin/env bash
# The README's commands run as written: the ```sh block under the heading with "five steps" (your own
# character in five steps) and the ```python block under the heading with "Python".
#  - The sh block runs in a temporary directory that stands in for the repository root: build/release/apps
#    and build/release/python link to the build's, tests/, data/ and scenes/ to the sources'. So the
#    README keeps its natural paths (build/release/apps/snh, output/limb) and every output directory the
#    steps write lands in the temporary directory. Each command must succeed, and the files the steps
#    promise must be there: both runs' frames, the report, the two pictures, flesh.usda.
#  - The python block is fed to the interpreter on its standard input (as if pasted) from the same
#    directory, with PYTHONPATH=build/release/python, and must exit 0 and print its results.
# Usage: test_readme.sh SOURCE_DIR APPS_DIR [PYTHON_DIR [PYTHON]]
#   SOURCE_DIR the repository root (README.md, tests/, data/, scenes/); APPS_DIR the directory of snh;
#   PYTHON_DIR the directory of the snh module (empty or absent: the python block is skipped, exit 77 if all
#   else passed); PYTHON the interpreter (default /usr/bin/python3, as the README says).
set -u
SRC="$1" APPS="$2" PYDIR="${3:-}" PYTHON="${4:-/usr/bin/python3}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
pass=0 fail=0
# shellcheck source=lib.sh
. "$(dirname "$0")/lib.sh"  # ok, bad

# extract README HEADING_REGEX LANG: the fenced blocks ```LANG in the section whose heading matches
# HEADING_REGEX (case-insensitive), each line as it is; a line "@@@ block" starts each block. Lines in a
# fence are never headings (a shell comment starts with # too).
extract() {
  awk -v h="$2" -v lang="$3" '
    fence && /^```/ { fence = 0; grab = 0; next }
    fence { if (grab) print; next }
    /^```/ { fence = 1; if (section && $0 == "```" lang) { grab = 1; print "@@@ block" } next }
    /^#+ / { section = (tolower($0) ~ h); next }
  ' "$1"
}

readme="$SRC/README.md"
[ -f "$readme" ] || { echo "FAIL: no $readme"; exit 1; }
extract "$readme" "five steps" sh > "$work/steps.txt"
extract "$readme" "python" python > "$work/python.txt"
[ "$(grep -c '^@@@ block' "$work/steps.txt")" -eq 1 ] && ok || bad "README: one \`\`\`sh block under the five steps heading (found $(grep -c '^@@@ block' "$work/steps.txt"))"
[ "$(grep -c '^@@@ block' "$work/python.txt")" -eq 1 ] && ok || bad "README: one \`\`\`python block under the Python heading (found $(grep -c '^@@@ block' "$work/python.txt"))"
grep -v '^@@@ block' "$work/steps.txt" > "$work/steps.sh"
grep -v '^@@@ block' "$work/python.txt" > "$work/snippet.py"
# Five steps, numbered 1 to 5 in the comments that introduce them.
[ "$(grep -oE '^# [0-9]+\.' "$work/steps.sh" | tr -d '# .' | tr '\n' ' ')" = "1 2 3 4 5 " ] && ok \
  || bad "README: the sh block has steps $(grep -oE '^# [0-9]+\.' "$work/steps.sh" | tr '\n' ' '), not # 1. to # 5."

# The stand-in for the repository root.
root="$work/root"
mkdir -p "$root/build/release"
ln -s "$(cd "$APPS" && pwd)" "$root/build/release/apps"
[ -n "$PYDIR" ] && ln -s "$(cd "$PYDIR" && pwd)" "$root/build/release/python"
for d in tests data scenes; do ln -s "$(cd "$SRC/$d" && pwd)" "$root/$d"; done

# The five steps, every command checked (set -e), in a shell of their own.
if (cd "$root" && bash -e -o pipefail "$work/steps.sh") > "$work/steps.log" 2>&1; then ok
else bad "README five steps: a command failed: $(tail -5 "$work/steps.log")"; fi
out="$root/output"
for f in limb/index.html limb/flesh.usda limb/bones.json limb/stats.json limb/surface/024.obj limb/lbs/024.obj limb/024.vtu; do
  [ -s "$out/$f" ] && ok || bad "README five steps: output/$f missing"
done
for png in limb_flesh.png limb_lbs.png; do  # a PNG's signature
  [ "$(head -c 8 "$out/$png" 2> /dev/null | od -An -c | tr -d ' ')" = '211PNG\r\n032\n' ] && ok || bad "README five steps: output/$png is not a PNG"
done
# The second run (step 3) replaced the first, finer, with its options, and every frame converged.
grep -q '"resolution": 20' "$out/limb/stats.json" && grep -q '"joint_cells": "free"' "$out/limb/stats.json" \
  && grep -q '"all_converged": true' "$out/limb/stats.json" && grep -q '"status": "finished"' "$out/limb/stats.json" \
  && ok || bad "README five steps: output/limb/stats.json is not step 3's finished run"
grep -q 'def Mesh "flesh"' "$out/limb/flesh.usda" && grep -q 'def Mesh "linear_blend_skinning"' "$out/limb/flesh.usda" \
  && ok || bad "README five steps: flesh.usda lacks its two meshes"

# `make demo` after the five steps (a newcomer may take either first): its runs, read from the Makefile's demo
# recipe, each write a folder of their own under output/, beside output/limb. A run into output/ itself was
# refused there, since output/ then held only the steps' folder and no run of its own.
grep -E '^\s+\$\(BUILD\)/apps/' "$SRC/Makefile" | sed 's/^[[:space:]]*//; s/\$(BUILD)/build\/release/g' > "$work/demo.sh"
[ "$(wc -l < "$work/demo.sh")" -ge 3 ] && ok || bad "Makefile: no demo recipe found ($(wc -l < "$work/demo.sh") program lines)"
if (cd "$root" && bash -e "$work/demo.sh") > "$work/demo.log" 2>&1; then ok
else bad "make demo after the README's five steps: $(tail -3 "$work/demo.log")"; fi
for f in stretch/index.html bunny_squash/index.html hand_fist/index.html limb/index.html; do
  [ -s "$out/$f" ] && ok || bad "make demo after the five steps: output/$f missing"
done

# The Python snippet, pasted into the interpreter.
if [ -z "$PYDIR" ]; then
  echo "test_readme: the python block skipped: no Python module directory given (the module was not built)"
else
  if (cd "$root" && PYTHONPATH=build/release/python PYTHONDONTWRITEBYTECODE=1 "$PYTHON" - < "$work/snippet.py") > "$work/python.log" 2>&1; then ok
  else bad "README python: $(tail -5 "$work/python.log")"; fi
  grep -q '^nu = 0.488: volume kept 0\.[0-9]*' "$work/python.log" && grep -q '^neo_hookean is defined there: False' "$work/python.log" \
    && ok || bad "README python: unexpected output: $(cat "$work/python.log")"
fi

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ] || exit 1
[ -n "$PYDIR" ] || exit 77
