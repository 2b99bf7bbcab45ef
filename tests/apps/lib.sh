# Shared by the shell tests: sourced, not run.
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

# expect_exit CODE NAME PATTERN -- COMMAND...: COMMAND exits with CODE and its output (stdout and stderr
# together) matches the extended regular expression PATTERN.
expect_exit() {
  local want="$1" name="$2" pattern="$3" out code
  shift 4
  out="$("$@" 2>&1)"
  code=$?
  if [ "$code" -eq "$want" ] && printf '%s' "$out" | grep -Eq -- "$pattern"; then ok; else bad "$name (exit $code): $out"; fi
}

# expect_error NAME PATTERN -- COMMAND...: COMMAND fails as bad input must: exit code 2 and one line
# matching PATTERN.
expect_error() {
  local name="$1" pattern="$2" out code
  shift 3
  out="$("$@" 2>&1)"
  code=$?
  if [ "$code" -eq 2 ] && [ "$(printf '%s\n' "$out" | wc -l)" -eq 1 ] && printf '%s' "$out" | grep -Eq -- "$pattern"; then ok
  else bad "$name (exit $code): $out"; fi
}
