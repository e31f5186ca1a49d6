#!/usr/bin/env bash
# bench/fps_plan on a layout read from calibration tables and on problems from target files: the
# table row and the summary carry every figure, an unsolvable target is named with its reason, and
# bad inputs are refused with a message.
set -euo pipefail
BENCH=${1:?usage: $0 PATH_TO_FPS_PLAN}
CAL="$(cd "$(dirname "$0")/../fps/data/calibration" && pwd)"
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
fail() { echo "FAIL: $*" >&2; [ -f "$TMP/out" ] && cat "$TMP/out" >&2; exit 1; }

# Robot 101 pointed up into guide camera 2's buffer (it cannot get there: parked, named); robot 104
# 0.35 mm outside that buffer (it can).
cat >"$TMP/targets.yaml" <<'YAML'
targets:
  - {robot: 101, alpha: 179.73, beta: 0}
  - {robot: 104, alpha: 90, beta: 40}
YAML
"$BENCH" --layout "$CAL" --problem "$TMP/targets.yaml" --problem random,random --problem folded,random >"$TMP/out" 2>&1 \
  || fail "fps_plan exited $?"
grep -q '^fps_plan: layout calibration: 6 robots' "$TMP/out" || fail "layout line"
row0=$(grep -E '^  0 ' "$TMP/out") || fail "no row for problem 0"
[ "$(awk '{print $2}' <<<"$row0")" = no ] || fail "problem 0 should not be solved: $row0"
grep -A2 -E '^  0 ' "$TMP/out" | grep -qE 'target parked: .*guide camera 2.*\(robot 101\)' \
  || fail "problem 0: the parked robot's reason is missing"
for k in 1 2; do
  row=$(grep -E "^  $k " "$TMP/out") || fail "no row for problem $k"
  # solved, plan_s engine_s check_s p_med p_max move_s overlap bound_s min_clr: numbers
  awk '{ for (i = 3; i <= 11; ++i) if ($i !~ /^[0-9.]+$/) exit 1 }' <<<"$row" || fail "problem $k: figures: $row"
done
bench=$(grep '^BENCH fps_plan ' "$TMP/out") || fail "no BENCH line"
for key in problems=3 solved= median_s= median_search_s= median_check_s= max_points= move_s= move_lattice_s= \
           move_random_s= random_ratio= bound_s= move_over_bound= min_clearance_mm=; do
  grep -q " $key" <<<"$bench" || fail "BENCH line lacks $key: $bench"
done
clr=$(sed -E 's/.* min_clearance_mm=([-0-9.]+).*/\1/' <<<"$bench")
awk -v c="$clr" 'BEGIN { exit !(c >= 0) }' || fail "smallest clearance $clr below 0"

# Bad inputs: a missing problem file is reported and fails the run; an unknown layout is refused.
rc=0; "$BENCH" --layout "$CAL" --problem "$TMP/none.yaml" >"$TMP/out" 2>&1 || rc=$?
[ "$rc" = 1 ] || fail "missing problem file: exit $rc, expected 1"
grep -q 'none.yaml' "$TMP/out" || fail "missing problem file not named"
rc=0; "$BENCH" --layout "$TMP/nowhere" >"$TMP/out" 2>&1 || rc=$?
[ "$rc" = 2 ] || fail "unknown layout: exit $rc, expected 2"
rc=0; "$BENCH" --problem >"$TMP/out" 2>&1 || rc=$?
[ "$rc" = 2 ] || fail "--problem without a value: exit $rc, expected 2"
echo "fps_plan inputs: ok"
