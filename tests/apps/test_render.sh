#!/usr/bin/env bash
# snh render with a real browser (Debian's chromium), issue 13:
#   twenty renders of one run in a row all succeed, each with one browser run (the picture is taken when
#   the page says it drew the frame; it used to be taken when a virtual-time budget ran out, and about
#   one browser run in eight on a busy machine had not drawn it yet), and none leaves a temporary file;
#   SIGINT, SIGTERM, or two SIGINTs, while the browser runs: exit 130 / 143, the browser's processes gone,
#   its temporary directory (profile and Chromium's own temporaries) removed, no picture written.
# Usage: test_render.sh SNH
set -u
SNH="$1"
work="$(mktemp -d)"
pid=""
trap '[ -n "$pid" ] && kill -9 "$pid" 2> /dev/null; rm -rf "$work"' EXIT
pass=0 fail=0
# shellcheck source=lib.sh
. "$(dirname "$0")/lib.sh"  # ok, bad, wait_for, expect_exit, expect_error

browser="$(command -v chromium || command -v chromium-browser)" || { echo "FAIL: chromium is not installed (scripts/install-deps installs it)"; exit 1; }
# The browser through a wrapper that counts its starts.
printf '#!/bin/sh\necho started >> "%s"\nexec "%s" "$@"\n' "$work/starts" "$browser" > "$work/browser"
chmod +x "$work/browser"
"$SNH" stretch --res 2 --steps 2 --out "$work/run" > /dev/null 2>&1 || bad "the run to render"

# browser_of DIR: the processes whose command line names DIR (the browser's profile is under it).
browser_of() { pgrep -f -- "$1" 2> /dev/null; }

# 1. Twenty renders in a row: every one succeeds with one browser run, and leaves nothing in TMPDIR.
mkdir -p "$work/tmp"
failed=0
for i in $(seq 1 20); do
  out="$(TMPDIR="$work/tmp" "$SNH" render "$work/run" --browser "$work/browser" --width 160 --height 120 --out "$work/r.png" 2>&1)"
  code=$?
  [ "$code" -eq 0 ] && [ "$out" = "$work/r.png (160x120)" ] || { failed=$((failed + 1)); echo "render $i (exit $code): $out"; }
done
starts=$(wc -l < "$work/starts")
[ "$failed" -eq 0 ] && ok || bad "$failed of 20 renders failed"
[ "$starts" -eq 20 ] && ok || bad "20 renders started the browser $starts times"
[ -z "$(ls -A "$work/tmp")" ] && ok || bad "the renders left temporary files: $(ls -A "$work/tmp" | head -3)"

# 2. A signal while the browser runs: 128 + the signal, the browser gone, its directory removed, no PNG.
# interrupt NAME SIGNAL...: starts a render, sends the signals (10 ms apart) once the browser runs.
interrupt() {
  local name="$1" want="$2" tmp="$work/tmp-$1"
  shift 2
  mkdir -p "$tmp"
  TMPDIR="$tmp" "$SNH" render "$work/run" --width 160 --height 120 --out "$work/$name.png" > "$work/$name.log" 2>&1 &
  pid=$!
  # Seen once is enough: asking again can miss it (a process in the middle of exec, as Debian's chromium
  # script is when it hands over to the browser, shows no command line for a moment).
  local i seen=""
  for ((i = 0; i < 1500; i++)); do
    seen="$(browser_of "$tmp/")"
    [ -n "$seen" ] && break
    sleep 0.02
  done
  [ -n "$seen" ] || { bad "$name: the browser did not start: $(cat "$work/$name.log")"; kill -9 "$pid"; wait "$pid"; return; }
  sleep 0.2
  local s
  for s in "$@"; do
    kill -"$s" "$pid"
    sleep 0.01
  done
  wait "$pid"
  local code=$?
  pid=""
  sleep 0.2  # the browser's processes are killed by then; let them be reaped
  [ "$code" -eq "$want" ] && ok || bad "$name: exit $code, not $want: $(cat "$work/$name.log")"
  # (A second signal may end the process once the browser is cleaned up, before the message.)
  [ $# -gt 1 ] || grep -q "^snh: interrupted by signal $((want - 128)): the browser was stopped, nothing was written$" \
    "$work/$name.log" && ok || bad "$name: message: $(cat "$work/$name.log")"
  [ -z "$(browser_of "$tmp/")" ] && ok || bad "$name: browser processes left: $(browser_of "$tmp/" | tr '\n' ' ')"
  [ -z "$(ls -A "$tmp")" ] && ok || bad "$name: temporary files left in TMPDIR: $(ls -A "$tmp")"
  [ ! -e "$work/$name.png" ] && ok || bad "$name: a picture was written"
}
interrupt sigint 130 INT
interrupt sigterm 143 TERM
interrupt two-sigints 130 INT INT

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
