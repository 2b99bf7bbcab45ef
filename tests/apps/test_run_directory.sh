#!/usr/bin/env bash
# The output directory holds one run, and says what state it is in (issue 11):
#   a run killed with SIGKILL leaves stats.json with status "running" and the report says "unfinished";
#   the header and every line reach a file while the run goes on (flushed);
#   a second run into a directory another run is writing to is refused at once (exit 2, one line);
#   a new run clears the previous run's frames, stats and report, and nothing else;
#   --resume refuses a missing frame and a damaged checkpoint; tetcli's run is resumed by `snh stretch`.
# Usage: test_run_directory.sh SNH TETCLI HEXCLI
set -u
SNH="$1" TETCLI="$2" HEXCLI="$3"
work="$(mktemp -d)"
pids=()
trap 'for p in "${pids[@]}"; do kill -9 "$p" 2> /dev/null; done; rm -rf "$work"' EXIT
pass=0 fail=0
# shellcheck source=lib.sh
. "$(dirname "$0")/lib.sh"  # ok, bad, wait_for, expect_exit, expect_error

# 1. The header is in the log as soon as the run starts, before step 1 ends (res 24 hexes: step 1 takes
#    a factorization of 46 875 unknowns); then SIGKILL after step 2: the stats say "running".
"$HEXCLI" 24 stable_neo_hookean 1.0 10.0 "$work/killed" > "$work/killed.log" 2>&1 &
pid=$!
pids+=("$pid")
if wait_for "$work/killed.log" "^mesh: " 60; then
  grep -q "^step   1/" "$work/killed.log" && bad "the header reached the log only with step 1's line" || ok
else
  bad "no header in the log within 60 s: $(cat "$work/killed.log")"
fi
if wait_for "$work/killed.log" "^step   2/" 120; then
  kill -9 "$pid"
  wait "$pid" 2> /dev/null
  s="$work/killed/stats.json"
  grep -q '"status": "running"' "$s" && grep -q '"all_converged": false' "$s" && ok || bad "killed run's stats: $(grep -E 'status|all_converged' "$s")"
  out="$("$SNH" report "$work/killed" 2>&1)"; code=$?
  [ "$code" -eq 0 ] && grep -q '"text":"unfinished: stats.json was last written while the run was going, after step [0-9]' \
    "$work/killed/report/data.js" && ok || bad "report of a killed run (exit $code): $out"
else
  bad "step 2 not reached in 120 s"
  kill -9 "$pid" 2> /dev/null
fi

# 2. Two runs into one directory at once: the second is refused before it touches anything.
"$TETCLI" 20 stable_neo_hookean 1.0 10.0 "$work/busy" > "$work/busy.log" 2>&1 &
pid=$!
pids+=("$pid")
if wait_for "$work/busy.log" "^step   1/" 60; then
  before="$(ls "$work/busy" | sort)"
  out="$("$SNH" stretch --res 2 --steps 2 --out "$work/busy" 2>&1)"; code=$?
  [ "$code" -eq 2 ] && [ "$(printf '%s\n' "$out" | wc -l)" -eq 1 ] &&
    printf '%s' "$out" | grep -q "^snh: error: another snh run is writing to $work/busy (process $pid)" && ok ||
    bad "second run into a busy directory (exit $code): $out"
  out="$("$TETCLI" 2 stable_neo_hookean 1.0 10.0 "$work/busy" 2>&1)"; code=$?
  [ "$code" -eq 2 ] && printf '%s' "$out" | grep -q "^tetcli: error: another snh run is writing to" && ok ||
    bad "tetcli into a busy directory (exit $code): $out"
  kill -INT "$pid"
  wait "$pid" 2> /dev/null
  grep -q '"status": "interrupted"' "$work/busy/stats.json" && ok || bad "the first run was disturbed: $(grep status "$work/busy/stats.json")"
else
  bad "the busy run did not start: $(cat "$work/busy.log")"
fi

# 3. A new run into a used directory: the previous run's files go, other files stay.
d="$work/again"
"$SNH" stretch --res 2 --steps 6 --out "$d" > /dev/null 2>&1
echo "my notes" > "$d/notes.txt"
[ -f "$d/006.obj" ] && [ -f "$d/index.html" ] && ok || bad "first run's files"
"$SNH" stretch --res 2 --steps 3 --out "$d" --no-report > /dev/null 2>&1
[ -f "$d/003.obj" ] && [ ! -e "$d/004.obj" ] && [ ! -e "$d/006.vtu" ] && [ ! -e "$d/index.html" ] && [ ! -e "$d/report" ] \
  && [ "$(cat "$d/notes.txt")" = "my notes" ] && grep -q '"steps_requested": 3' "$d/stats.json" && ok ||
  bad "the second run left the first one's files: $(ls "$d")"
grep -q '"status": "finished"' "$d/stats.json" && ok || bad "status of a finished run"

# A directory with a file of one of our names but no run of ours: refused, and the file kept.
d="$work/theirs"
mkdir -p "$d" && echo "<html>my page</html>" > "$d/index.html"
out="$("$SNH" stretch --res 2 --steps 2 --out "$d" 2>&1)"; code=$?
[ "$code" -eq 2 ] && [ "$out" = "snh: error: $d: is not empty and holds no snh run (it has index.html): refusing to write a run into it; choose an empty or new output directory, or pass --force to write there anyway" ] \
  && [ "$(cat "$d/index.html")" = "<html>my page</html>" ] && [ -z "$(ls -A "$d" | grep -v index.html)" ] \
  && ok || bad "a directory that is not ours (exit $code): $out"
# Any file of someone else's (not only ours by name) makes a directory theirs: the paper's programs and
# every snh command refuse it (tetcli once wrote 60 files into /); --force writes there anyway.
d="$work/foreign"
mkdir -p "$d" && echo "mine" > "$d/notes.txt"
for cmd in "stretch --res 2 --steps 2 --out $d" "lab --quick --energy arap --out $d"; do
  out="$(timeout 60 "$SNH" $cmd 2>&1)"; code=$?
  [ "$code" -eq 2 ] && [ "$(printf '%s\n' "$out" | wc -l)" -eq 1 ] && printf '%s' "$out" | grep -q "$d: is not empty and holds no snh run (it has notes.txt)" \
    && [ "$(ls -A "$d")" = "notes.txt" ] && ok || bad "snh $cmd into a foreign directory (exit $code): $out"
done
cp "$(dirname "$0")/../../scenes/inverted_cube.json" "$work/tiny.json"
out="$(timeout 60 "$SNH" run "$work/tiny.json" --out "$d" 2>&1)"; code=$?
[ "$code" -eq 2 ] && printf '%s' "$out" | grep -q "$d: is not empty and holds no snh run" && [ "$(ls -A "$d")" = "notes.txt" ] \
  && ok || bad "snh run into a foreign directory (exit $code): $out"
"$SNH" stretch --res 2 --steps 2 --out "$d" --force --no-report > /dev/null 2>&1 && [ -f "$d/002.obj" ] && [ "$(cat "$d/notes.txt")" = mine ] \
  && ok || bad "stretch --force into a foreign directory: $(ls -A "$d")"

# 4. --resume checks what it keeps: the frames, and the checkpoint's checksum.
d="$work/resume"
"$SNH" stretch --res 2 --steps 4 --out "$d" --no-report > /dev/null 2>&1
rm "$d/002.obj"
out="$("$SNH" stretch --res 2 --steps 4 --out "$d" --resume 2>&1)"; code=$?
[ "$code" -eq 2 ] && printf '%s' "$out" | grep -q "cannot resume: $d/002.obj is missing" && ok || bad "resume without a frame (exit $code): $out"
"$SNH" stretch --res 2 --steps 4 --out "$d" --no-report > /dev/null 2>&1
printf '\x55' | dd of="$d/checkpoint.bin" bs=1 seek=40 conv=notrunc status=none
out="$("$SNH" stretch --res 2 --steps 4 --out "$d" --resume 2>&1)"; code=$?
[ "$code" -eq 2 ] && printf '%s' "$out" | grep -q "damaged checkpoint (its checksum does not match" && ok ||
  bad "resume from a damaged checkpoint (exit $code): $out"

# 5. tetcli and hexcli write checkpoints; `snh stretch` with the same settings (their solver: pcg) resumes them.
d="$work/tetcli"
"$TETCLI" 3 stable_neo_hookean 1.0 10.0 "$d" > /dev/null 2>&1
out="$("$SNH" stretch --element tet --res 3 --mu 1 --lambda 10 --solver pcg --out "$d" --resume 2>&1)"; code=$?
[ "$code" -eq 0 ] && printf '%s' "$out" | grep -q "^resuming after step 25" && printf '%s' "$out" | grep -q "converged every step" \
  && ok || bad "snh stretch --resume of a tetcli run (exit $code): $out"
out="$("$SNH" stretch --element tet --res 3 --material neo_hookean --out "$d" --resume 2>&1)"; code=$?
[ "$code" -eq 2 ] && printf '%s' "$out" | grep -q "used other settings" && ok || bad "resume with another material (exit $code): $out"

# 6. A run refused after its directory was made (the multigrid solver on tets is refused when the solver is
# built) leaves no directory behind; one that existed stays.
out="$("$SNH" stretch --res 3 --solver mg --out "$work/mg_tets" 2>&1)"; code=$?
[ "$code" -eq 2 ] && printf '%s' "$out" | grep -q "needs a hexahedral lattice" && [ ! -e "$work/mg_tets" ] && ok \
  || bad "mg on tets (exit $code, directory $( [ -e "$work/mg_tets" ] && echo left || echo gone)): $out"
mkdir "$work/mg_given"
"$SNH" stretch --res 3 --solver mg --out "$work/mg_given" > /dev/null 2>&1
[ -d "$work/mg_given" ] && ok || bad "an output directory that was there before a refused run is gone"

# 7. --out naming a file or a FIFO is a refused path (bad input: exit 2, one line), left as it was; tetcli and
# snh stretch alike.
printf 'mine\n' > "$work/a_file"
mkfifo "$work/a_fifo"
expect_error "out is a file" "a_file exists and is not a directory" -- "$SNH" stretch --res 2 --out "$work/a_file"
expect_error "out is a FIFO" "a_fifo exists and is not a directory" -- "$SNH" stretch --res 2 --out "$work/a_fifo"
expect_error "tetcli out is a file" "a_file exists and is not a directory" -- "$TETCLI" 2 stable_neo_hookean 1.0 10.0 "$work/a_file"
[ "$(cat "$work/a_file")" = mine ] && [ -p "$work/a_fifo" ] && ok || bad "a refused --out was changed"

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
