#!/usr/bin/env bash
# Every scene in tests/data/malformed_scenes/ makes `snh run` fail before any work: exit code 2, one line
# on stderr that contains its .expected sibling (which names the file or value at fault), no output
# directory made, within 20 s (no hang).
# Usage: test_malformed_scenes.sh SNH DIR
set -u
SNH="$1" DIR="$2"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
# shellcheck source=lib.sh
. "$(dirname "$0")/lib.sh"  # ok, bad, wait_for, expect_exit, expect_error
cd "$DIR" || exit 1
pass=0 fail=0
for expected in *.expected; do
  file="${expected%.expected}"
  want="$(cat "$expected")"
  out="$(timeout 20 "$SNH" run "$file" --out "$work/${file%.json}" --no-report 2>&1)"; code=$?
  if [ "$code" -eq 2 ] && [ "$(printf '%s\n' "$out" | wc -l)" -eq 1 ] && [[ "$out" == "snh: error: $want"* ]] \
     && [ ! -e "$work/${file%.json}" ]; then
    ok
  else
    bad "$file (exit $code): $out"
    echo "      expected: snh: error: $want"
  fi
done
# every scene file has its expectation
for f in *.json; do [ -f "$f.expected" ] || bad "$f has no $f.expected"; done
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ] && [ "$pass" -gt 0 ]
