#!/usr/bin/env bash
# bench/closed_loop/matrix.sh with a stand-in for pepper_app that records its arguments and
# writes the JSON it is asked for: the selected configuration runs once with the world and the
# disturbance of its name, every --set reaches evaluate, a finished configuration is skipped on
# a second call, and an unknown option is refused.
set -euo pipefail
SRC=$(cd "$(dirname "$0")/../.." && pwd)
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
cat > "$TMP/app" <<'APP'
#!/usr/bin/env bash
echo "$*" >> "$(dirname "$0")/calls"
while [[ $# -gt 0 ]]; do
  if [[ $1 == --json ]]; then echo '{"format":"pepper.evaluation"}' > "$2"; fi
  shift
done
APP
chmod +x "$TMP/app"
run() { "$SRC/bench/closed_loop/matrix.sh" --out "$TMP/out" --app "$TMP/app" --gen-seeds 0 "$@"; }

run --only '^robotics_room_light0.6$' --set navigator.switching.min_next_scale_ratio=0 \
    --set navigator.hold_s=0.5 > "$TMP/log"
[[ $(wc -l < "$TMP/calls") -eq 1 ]] || fail "one evaluate call expected: $(cat "$TMP/calls")"
call=$(cat "$TMP/calls")
for want in "evaluate" "--world worlds/robotics_room.yaml" "--light-factor 0.6" \
            "--set navigator.switching.min_next_scale_ratio=0 --set navigator.hold_s=0.5" \
            "--size 640x480" "--starts 10"; do
  [[ $call == *"$want"* ]] || fail "'$want' not in: $call"
done
[[ -s $TMP/out/robotics_room_light0.6.json ]] || fail "no JSON for the configuration"

# Resumed: the finished configuration is skipped; without --set nothing is added.
run --only '^robotics_room_(light0.6|none)$' > "$TMP/log2"
grep -q "skip robotics_room_light0.6" "$TMP/log2" || fail "finished configuration not skipped"
[[ $(wc -l < "$TMP/calls") -eq 2 ]] || fail "exactly one more call expected"
[[ $(tail -1 "$TMP/calls") != *"--set"* ]] || fail "a --set without --set: $(tail -1 "$TMP/calls")"

# Stopped: its runs stop too (no stand-in left running) and leave no JSON behind.
cat > "$TMP/slow" <<'APP'
#!/usr/bin/env bash
echo $$ >> "$(dirname "$0")/slow_pids"
sleep 30
APP
chmod +x "$TMP/slow"
"$SRC/bench/closed_loop/matrix.sh" --out "$TMP/out2" --app "$TMP/slow" --gen-seeds 0 \
    --only '^robotics_room_(none|person)$' --jobs 2 > "$TMP/log4" 2>&1 &
M=$!
for _ in $(seq 50); do
  [[ -f $TMP/slow_pids && $(wc -l < "$TMP/slow_pids") -ge 2 ]] && break
  sleep 0.1
done
[[ $(wc -l < "$TMP/slow_pids") -eq 2 ]] || fail "two runs expected side by side"
kill -TERM "$M"
wait "$M" || true
sleep 0.5
while read -r pid; do
  # A killed process not yet reaped (a zombie: a container's init may be slow) has ended.
  state=$(ps -o stat= -p "$pid" 2> /dev/null || true)
  if [[ -n $state && $state != Z* ]]; then fail "run $pid still running after matrix.sh stopped"; fi
done < "$TMP/slow_pids"
ls "$TMP"/out2/*.json > /dev/null 2>&1 && fail "a stopped run left a JSON"
grep -q "stopped; the same command resumes" "$TMP/log4" || fail "no message when stopped"

# Fresh generated worlds: the seeds start where asked, the kind follows the seed.
listed=$(run --gen-seeds 2 --gen-first-seed 101 --only '^gen_' --list | tr '\n' ' ')
[[ $listed == "gen_corridor_101_none gen_corridor_101_light0.7 gen_building_102_none "* ]] ||
  fail "--gen-first-seed 101: $listed"

if run --bogus > "$TMP/log3" 2>&1; then fail "--bogus accepted"; fi
grep -q "unknown option --bogus" "$TMP/log3" || fail "no message for an unknown option"
echo "matrix.sh: ok"
