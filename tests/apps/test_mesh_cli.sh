#!/usr/bin/env bash
# `snh info`, `snh convert` and `snh stretch --mesh`: round trips through every writable format, the
# report's lines, and one-line errors with exit code 2.
# Usage: test_mesh_cli.sh SNH
set -u
SNH="$1"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
pass=0 fail=0
# shellcheck source=lib.sh
. "$(dirname "$0")/lib.sh"  # ok, bad, wait_for, expect_exit, expect_error

# Two tets, the second inverted in the file.
printf '5 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n' > "$work/t.node"
printf '2 4 0\n1 1 2 3 4\n2 2 4 3 5\n' > "$work/t.ele"
out="$("$SNH" info "$work/t.ele" 2>&1)" && ok || bad "info: $out"
printf '%s' "$out" | grep -q "tet4, 5 vertices, 2 cells, 6 boundary triangles" && ok || bad "info counts: $out"
printf '%s' "$out" | grep -q "rest volume: total 0.5" && ok || bad "info volume: $out"
printf '%s' "$out" | grep -q "problems: 1 inverted cell(s), re-oriented when used" && ok || bad "info problems: $out"
# t.ele -> .msh -> .mesh -> .vtu: the same mesh each time, re-oriented once.
"$SNH" convert "$work/t.ele" "$work/t.msh" | grep -q "(1 re-oriented)" && ok || bad "convert to msh"
"$SNH" convert "$work/t.msh" "$work/t.mesh" > /dev/null && "$SNH" convert "$work/t.mesh" "$work/t.vtu" > /dev/null && ok || bad "convert chain"
for f in t.msh t.mesh t.vtu; do
  "$SNH" info "$work/$f" | grep -q "problems: none" && ok || bad "info $f"
done
# Errors.
printf '2 4 0\n1 1 2 3 4\n' > "$work/t.ele"
out="$("$SNH" info "$work/t.ele" 2>&1)"; code=$?
[ "$code" -eq 2 ] && [ "$(printf '%s\n' "$out" | wc -l)" -eq 1 ] && printf '%s' "$out" | grep -q "t.ele:3: the file ends where a tetrahedron index was expected" \
  && ok || bad "truncated (exit $code): $out"
out="$("$SNH" convert "$work/t.msh" "$work/t.stl" 2>&1)"; code=$?
[ "$code" -eq 2 ] && printf '%s' "$out" | grep -q "cannot write '.stl' meshes" && ok || bad "bad output format (exit $code): $out"
# Writers replace only regular files: a FIFO, a device or a directory at the output path is refused
# (exit 2) and left as it was; a write that fails (here a file size limit: EFBIG, as a full disk) exits 3
# and leaves neither the file nor its temporary.
mkfifo "$work/fifo.msh"
out="$(timeout 20 "$SNH" convert "$work/t.msh" "$work/fifo.msh" 2>&1)"; code=$?
[ "$code" -eq 2 ] && [ "$out" = "snh: error: $work/fifo.msh: is a FIFO, not a regular file: refusing to replace it" ] && [ -p "$work/fifo.msh" ] \
  && ok || bad "convert to a FIFO (exit $code): $out"
mkdir "$work/dir.vtu"
out="$(timeout 20 "$SNH" convert "$work/t.msh" "$work/dir.vtu" 2>&1)"; code=$?
[ "$code" -eq 2 ] && [ "$out" = "snh: error: $work/dir.vtu: is a directory, not a regular file: refusing to replace it" ] && [ -d "$work/dir.vtu" ] \
  && ok || bad "convert to a directory (exit $code): $out"
if mknod "$work/null.mesh" c 1 3 2> /dev/null; then
  out="$(timeout 20 "$SNH" convert "$work/t.msh" "$work/null.mesh" 2>&1)"; code=$?
  [ "$code" -eq 2 ] && printf '%s' "$out" | grep -q "null.mesh: is a character device, not a regular file: refusing to replace it" \
    && [ -c "$work/null.mesh" ] && ok || bad "convert to a device (exit $code): $out"
fi
out="$( (trap '' XFSZ; ulimit -f 0; timeout 20 "$SNH" convert "$work/t.msh" "$work/full.vtu") 2>&1)"; code=$?
[ "$code" -eq 3 ] && [ "$out" = "snh: error: cannot write $work/full.vtu: File too large" ] && [ -z "$(ls "$work" | grep full)" ] \
  && ok || bad "convert onto a full disk (exit $code): $out"
# Input files are checked before they are read: a directory as a scene, a mesh file that is /dev/zero
# (never read: it has no end), 10 MB of zeros named .msh (fails on its first line, at once).
out="$(timeout 20 "$SNH" run "$work" 2>&1)"; code=$?
[ "$code" -eq 2 ] && [ "$out" = "snh: error: $work: is a directory, not a scene file" ] && ok || bad "run a directory (exit $code): $out"
printf '{"mesh": {"file": "/dev/zero"}}\n' > "$work/zero.json"
out="$(timeout 20 "$SNH" run "$work/zero.json" --out "$work/zero" 2>&1)"; code=$?
[ "$code" -eq 2 ] && printf '%s' "$out" | grep -q "/dev/zero: is not a regular file (a character device): cannot read a mesh file from it" \
  && ok || bad "mesh.file /dev/zero (exit $code): $out"
head -c 10000000 /dev/zero > "$work/zeros.msh"
out="$(timeout 20 "$SNH" info "$work/zeros.msh" 2>&1)"; code=$?
[ "$code" -eq 2 ] && [ "$out" = "snh: error: $work/zeros.msh:1: binary data (a NUL byte) where text was expected" ] \
  && ok || bad "info on zeros (exit $code): $out"
# snh stretch --mesh: a small hex mesh file, pulled along z.
printf '$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n12\n' > "$work/b.msh"
n=1; for k in 0 1 2; do for j in 0 1; do for i in 0 1; do printf '%d %d %d %d\n' $n $i $j $k >> "$work/b.msh"; n=$((n + 1)); done; done; done
printf '$EndNodes\n$Elements\n2\n1 5 0 1 2 4 3 5 6 8 7\n2 5 0 5 6 8 7 9 10 12 11\n$EndElements\n' >> "$work/b.msh"
out="$("$SNH" stretch --mesh "$work/b.msh" --axis z --steps 3 --stretch 1.3 --out "$work/s" 2>&1)" && ok || bad "stretch --mesh: $out"
printf '%s' "$out" | grep -q "mesh $work/b.msh" && printf '%s' "$out" | grep -q "2 cubes, 3 steps to a 1.3x stretch along z" && ok || bad "stretch header: $out"
grep -q '"axis": "z"' "$work/s/stats.json" && grep -q '"mesh_file"' "$work/s/stats.json" && ok || bad "stretch stats"
out="$("$SNH" stretch --mesh "$work/missing.msh" --out "$work/s2" 2>&1)"; code=$?
[ "$code" -eq 2 ] && printf '%s' "$out" | grep -q "cannot open the mesh file" && ok || bad "missing mesh (exit $code): $out"

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
