#!/usr/bin/env bash
# `axon sim fps --layout default --http 127.0.0.1:0`: the web server of a 500-robot simulated plane.
#   1. /metrics passes Prometheus's own linter (`promtool check metrics`) and has the fps counters;
#   2. /api/state has every robot, /api/fps/info the layout, / lists the fps page, the page is served;
#   3. a malformed request is answered 400 and counted in /metrics.
source "$(dirname "$0")/lib.sh"
command -v promtool >/dev/null || fail "promtool not found (Debian's prometheus package; scripts/install-deps.sh)"

"$AXON" sim fps --layout default --folded --http 127.0.0.1:0 >"$TMP/sim.out" 2>"$TMP/sim.err" &
PIDS+=($!)
wait_for_line "$TMP/sim.out" '^ready$' 60 >/dev/null
URL=http://$(wait_for_line "$TMP/sim.out" '^listening http ' | awk '{print $3}')

# 1. Prometheus's linter: names, units, HELP and TYPE lines.
curl -sSf "$URL/metrics" >"$TMP/metrics.txt" || fail "GET /metrics"
promtool check metrics <"$TMP/metrics.txt" >"$TMP/promtool.out" 2>&1 || { cat "$TMP/promtool.out" >&2; fail "promtool check metrics"; }
for name in axon_fps_sim_robots axon_fps_sim_frames_processed_total axon_fps_sim_collisions_total \
            axon_fps_sim_receive_overflows_total axon_fps_sim_robot_requests_total axon_fps_sim_bus_locks_total \
            axon_fps_sim_bus_busy_seconds_total axon_web_http_requests_total axon_web_websocket_dropped_total; do
  grep -q "^# TYPE $name " "$TMP/metrics.txt" || fail "no $name in /metrics"
done
grep -q '^axon_fps_sim_robots{state="ready"} 500$' "$TMP/metrics.txt" || fail "500 ready robots expected"
[ "$(grep -c '^axon_fps_sim_robot_requests_total{' "$TMP/metrics.txt")" = 500 ] || fail "one request counter per robot expected"

# 2. The JSON endpoints and the page.
curl -sSf "$URL/api/state" >"$TMP/state.json" || fail "GET /api/state"
/usr/bin/python3 - "$TMP/state.json" <<'PY' || fail "/api/state"
import json, sys
state = json.load(open(sys.argv[1]))["fps"]
assert len(state["robots"]) == 500, len(state["robots"])
assert state["lock"]["locked"] is False, state["lock"]
PY
# get PATH: the body of GET PATH in $TMP/body (grep -q must not read from curl's pipe: pipefail).
get() { curl -sSf "$URL$1" >"$TMP/body" || fail "GET $1"; }
get /api/fps/info && grep -q '"layout":"default"' "$TMP/body" || fail "/api/fps/info has not the layout"
get / && grep -q 'href="/fps.html"' "$TMP/body" || fail "the index does not list the fps page"
get /fps.html && grep -q '<canvas id="plane"' "$TMP/body" || fail "/fps.html is not the page"
get /fps.js

# 3. Malformed input: 400, counted.
HOSTPORT=${URL#http://}
exec 3<>"/dev/tcp/${HOSTPORT%:*}/${HOSTPORT#*:}"
printf 'GARBAGE\x01 / HTTP/9\r\n\r\n' >&3
status=$(head -n1 <&3 | tr -d '\r')
exec 3<&-
[ "$status" = "HTTP/1.1 400 Bad Request" ] || fail "a malformed request should get 400 (got '$status')"
get /metrics && grep -q '^axon_web_http_bad_requests_total 1$' "$TMP/body" || fail "the malformed request was not counted"
echo PASS
