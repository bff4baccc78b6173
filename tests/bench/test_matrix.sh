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

run --only '^robotics_room_light0.6$' --set navigator.arrival_fade_ratio=0 \
    --set navigator.turn_feedforward=0 > "$TMP/log"
[[ $(wc -l < "$TMP/calls") -eq 1 ]] || fail "one evaluate call expected: $(cat "$TMP/calls")"
call=$(cat "$TMP/calls")
for want in "evaluate" "--world worlds/robotics_room.yaml" "--light-factor 0.6" \
            "--set navigator.arrival_fade_ratio=0 --set navigator.turn_feedforward=0" \
            "--size 640x480" "--starts 10"; do
  [[ $call == *"$want"* ]] || fail "'$want' not in: $call"
done
[[ -s $TMP/out/robotics_room_light0.6.json ]] || fail "no JSON for the configuration"

# Resumed: the finished configuration is skipped; without --set nothing is added.
run --only '^robotics_room_(light0.6|none)$' > "$TMP/log2"
grep -q "skip robotics_room_light0.6" "$TMP/log2" || fail "finished configuration not skipped"
[[ $(wc -l < "$TMP/calls") -eq 2 ]] || fail "exactly one more call expected"
[[ $(tail -1 "$TMP/calls") != *"--set"* ]] || fail "a --set without --set: $(tail -1 "$TMP/calls")"

if run --bogus > "$TMP/log3" 2>&1; then fail "--bogus accepted"; fi
grep -q "unknown option --bogus" "$TMP/log3" || fail "no message for an unknown option"
echo "matrix.sh: ok"
