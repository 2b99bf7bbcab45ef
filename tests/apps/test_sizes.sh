#!/usr/bin/env bash
# The library stays readable: no source file in src/ over 800 lines, and no function over 120 lines unless
# the comment just above it gives the reason (a line with "over 120 lines:"). Functions are measured by
# pmccabe (Debian's pmccabe: the lines from a function's first to its last). One line per file or function at
# fault, and a non-zero exit code; exit 77 (skipped) where pmccabe is missing.
# Usage: test_sizes.sh SRC_DIR
set -u
SRC="$1"
command -v pmccabe > /dev/null || { echo "sizes: skipped: pmccabe is not installed (scripts/install-deps installs it)"; exit 77; }
bad=0 files=0 functions=0
while IFS= read -r file; do
  files=$((files + 1))
  lines=$(wc -l < "$file")
  if [ "$lines" -gt 800 ]; then
    echo "FAIL: ${file#"$SRC"/}: $lines lines (at most 800: split it by concern)"
    bad=$((bad + 1))
  fi
done < <(find "$SRC" -name '*.cpp' -o -name '*.hpp' | sort)
# pmccabe: complexity, complexity, statements, first line, lines, file(line): function
while read -r _ _ _ first count where name; do
  functions=$((functions + 1))
  [ "$count" -gt 120 ] || continue
  file=${where%%(*}
  from=$((first > 6 ? first - 6 : 1))
  if sed -n "${from},${first}p" "$file" | grep -q "over 120 lines:"; then continue; fi
  echo "FAIL: ${file#"$SRC"/}:$first: $name is $count lines (at most 120, or a comment above it saying why: \"over 120 lines: ...\")"
  bad=$((bad + 1))
done < <(find "$SRC" -name '*.cpp' -o -name '*.hpp' | sort | xargs pmccabe 2>/dev/null)
echo "sizes: $files files, $functions functions checked, $bad too long"
[ "$bad" -eq 0 ] && [ "$files" -gt 50 ] && [ "$functions" -gt 500 ]
