# Shared by the shell tests that watch a running program: sourced, not run.
# ok / bad count checks (the caller prints "$pass passed, $fail failed" and sets pass=0 fail=0).
ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "FAIL: $*"; }

# wait_for FILE PATTERN SECONDS: true once FILE has a line matching PATTERN.
wait_for() {
  local i
  for ((i = 0; i < $3 * 50; i++)); do
    grep -q -- "$2" "$1" 2> /dev/null && return 0
    sleep 0.02
  done
  return 1
}
