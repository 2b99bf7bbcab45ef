#!/usr/bin/env bash
# Every file in tests/data/malformed/ makes `snh info` fail with exit code 2 and one line that names
# the file and contains the error in its .expected sibling.
# Usage: test_malformed.sh SNH DIR
set -u
SNH="$1" DIR="$2"
pass=0 fail=0
# shellcheck source=lib.sh
. "$(dirname "$0")/lib.sh"  # ok, bad, wait_for, expect_exit, expect_error
for expected in "$DIR"/*.expected; do
  file="${expected%.expected}"
  want="$(cat "$expected")"
  out="$("$SNH" info "$file" 2>&1)"; code=$?
  if [ "$code" -eq 2 ] && [ "$(printf '%s\n' "$out" | wc -l)" -eq 1 ] && [[ "$out" == *"$file"* ]] && [[ "$out" == *"$want"* ]]; then
    ok
  else
    bad "$(basename "$file") (exit $code): $out"
    echo "      expected: $want"
  fi
done
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ] && [ "$pass" -gt 0 ]
