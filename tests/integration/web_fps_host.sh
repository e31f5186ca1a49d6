#!/usr/bin/env bash
# `axon fps plane --layout ... --http 127.0.0.1:0 move ...`: the host's view of a 500-robot plane
# (`axon sim fps --layout default`) while it drives it.
#   1. /api/fps/info is the layout with "view":"host"; /metrics passes `promtool check metrics`
#      during the move and has the host's counters per bus;
#   2. after the move (--http-linger keeps the page up) /api/fps/state has 500 robots, ready, at the
#      move's target angles, the lock off.
source "$(dirname "$0")/lib.sh"
command -v promtool >/dev/null || fail "promtool not found (Debian's prometheus package; scripts/install-deps.sh)"

start_plane sim default
"$AXON" fps plane --layout "$TMP/sim.yaml" --http 127.0.0.1:0 --http-linger 30 move --alpha 30 --beta 150 --duration 4 \
  --fit-duration >"$TMP/move.out" 2>"$TMP/move.err" &
MOVE=$!
PIDS+=($MOVE)
URL=http://$(wait_for_line "$TMP/move.out" '^listening http ' | awk '{print $3}')

# get PATH: the body of GET PATH in $TMP/body.
get() { curl -sSf --retry 5 --retry-connrefused --retry-delay 1 "$URL$1" >"$TMP/body" || fail "GET $1"; }

# 1. The layout, and the metrics while the host works.
get /api/fps/info
grep -q '"view":"host","layout":"default"' "$TMP/body" || fail "/api/fps/info is not the host's view of the layout"
get /metrics
cp "$TMP/body" "$TMP/metrics.txt"
promtool check metrics <"$TMP/metrics.txt" >"$TMP/promtool.out" 2>&1 || { cat "$TMP/promtool.out" >&2; fail "promtool check metrics"; }
for name in axon_fps_host_robots axon_fps_host_locked axon_fps_host_bus_requests_total axon_fps_host_bus_timeouts_total \
            axon_fps_host_bus_retries_total axon_fps_host_bus_late_replies_total axon_fps_host_bus_collision_reports_total \
            axon_fps_host_bus_receive_overflows_total axon_fps_host_robot_collision_reports_total axon_web_http_requests_total; do
  grep -q "^# TYPE $name " "$TMP/metrics.txt" || fail "no $name in /metrics"
done

# 2. The end of the move as the host sees it: wait for the report, then for every robot at the target.
wait_for_line "$TMP/move.out" '^completed: 500 robots' 120 >/dev/null || { cat "$TMP/move.err" >&2; fail "the move did not complete"; }
ok=0
for _ in $(seq 1 40); do
  get /api/fps/state
  if /usr/bin/python3 - "$TMP/body" 2>/dev/null <<'PY'
import json, sys
state = json.load(open(sys.argv[1]))
robots = state["robots"]
assert len(robots) == 500, len(robots)
assert state["lock"]["locked"] is False, state["lock"]
assert state["states"]["ready"] == 500, state["states"]
far = [r for r in robots if r["a"] is None or abs(r["a"] - 30) > 0.1 or abs(r["b"] - 150) > 0.1]
assert not far, far[:3]
PY
  then ok=1; break; fi
  sleep 0.5
done
[ $ok = 1 ] || fail "the host's view does not show every robot at the target (last state in $TMP/body)"
# The metrics are rebuilt once a second: they follow.
ok=0
for _ in $(seq 1 10); do
  get /metrics
  if grep -q '^axon_fps_host_robots{state="ready"} 500$' "$TMP/body"; then ok=1; break; fi
  sleep 0.5
done
[ $ok = 1 ] || fail "500 ready robots expected in /metrics"
promtool check metrics <"$TMP/body" >"$TMP/promtool.out" 2>&1 || { cat "$TMP/promtool.out" >&2; fail "promtool check metrics (after)"; }
kill -INT $MOVE
wait $MOVE || fail "fps plane move exited $? (a signal during --http-linger is its normal end)"
echo PASS
