#!/usr/bin/env bash
# `axon blmc pd --http 127.0.0.1:0` against `axon sim blmc`: the board's web server.
#   1. /metrics passes Prometheus's own linter (`promtool check metrics`) and has the blmc families:
#      the loop's cycles and jitter histogram (one observation per period), overruns, errors by code,
#      safety stops by kind, the limits in force;
#   2. /api/blmc/state has the decimated traces (50 samples a second, one per 20 ms, not one per cycle) and the
#      loop's figures, /api/blmc/info the limits given on the command line; the index lists the blmc
#      page, and Chart.js is served from Debian's libjs-chart.js.
source "$(dirname "$0")/lib.sh"
command -v promtool >/dev/null || fail "promtool not found (Debian's prometheus package; scripts/install-deps.sh)"

printf 'alignment_s: 0.2\n' >"$TMP/board.yaml"
"$AXON" sim blmc --socketcand 127.0.0.1:0 --config "$TMP/board.yaml" --no-realtime >"$TMP/sim.out" 2>"$TMP/sim.err" &
PIDS+=($!)
PORT=$(wait_for_line "$TMP/sim.out" '^listening socketcand ' | sed 's/.*://')
# The run lasts 2 s; the page stays up 30 s more (the test ends it). Generous stale and receive
# limits: a loaded machine must not end the run in a safety stop.
"$AXON" blmc --socketcand "127.0.0.1:$PORT/can0" --no-realtime --stale-ms 1000 --recv-timeout-ms 0 --max-current 1.5 \
  --http 127.0.0.1:0 \
  --http-linger 30 pd --amplitude 0.2 --frequency 1 --duration 2 >"$TMP/pd.out" 2>"$TMP/pd.err" &
PIDS+=($!)
URL=http://$(wait_for_line "$TMP/pd.out" '^listening http ' | awk '{print $3}')
wait_for_line "$TMP/pd.out" '^motor 1: tracking error' 30 >/dev/null

# 1. Prometheus's linter, then the families.
curl -sSf "$URL/metrics" >"$TMP/metrics.txt" || fail "GET /metrics"
promtool check metrics <"$TMP/metrics.txt" >"$TMP/promtool.out" 2>&1 || { cat "$TMP/promtool.out" >&2; fail "promtool check metrics"; }
for name in axon_blmc_loop_cycles_total axon_blmc_loop_overruns_total axon_blmc_loop_jitter_seconds \
            axon_blmc_loop_records_lost_total axon_blmc_current_amperes axon_blmc_position_revolutions \
            axon_blmc_velocity_revolutions_per_second axon_blmc_status_flag axon_blmc_error_code \
            axon_blmc_board_errors_total axon_blmc_safety_stops_total axon_blmc_limit_max_current_amperes \
            axon_web_http_requests_total; do
  grep -q "^# TYPE $name " "$TMP/metrics.txt" || fail "no $name in /metrics"
done
grep -q '^# TYPE axon_blmc_loop_jitter_seconds histogram$' "$TMP/metrics.txt" || fail "the jitter is not a histogram"
value() { awk -v n="$1" '$1 == n {print $2}' "$TMP/metrics.txt"; }
cycles=$(value axon_blmc_loop_cycles_total)
periods=$(value axon_blmc_loop_jitter_seconds_count)
lost=$(value axon_blmc_loop_records_lost_total)
[ "$cycles" -gt 500 ] || fail "only $cycles cycles in a 2 s run"
[ "$periods" -eq $((cycles - 1 - lost)) ] || fail "$periods jitter observations for $cycles cycles ($lost records lost)"
grep -q '^axon_blmc_limit_max_current_amperes{board="can0"} 1.5$' "$TMP/metrics.txt" || fail "--max-current not in force"
grep -q '^axon_blmc_safety_stops_total{board="can0",kind="stale_data"} 0$' "$TMP/metrics.txt" || fail "no stale-data stop count"
grep -q '^axon_blmc_loop_running 0$' "$TMP/metrics.txt" || fail "the loop still running after the report"

# 2. The JSON endpoints, the index and Chart.js.
curl -sSf "$URL/api/blmc/info" >"$TMP/info.json" || fail "GET /api/blmc/info"
/usr/bin/python3 - "$URL" "$TMP/info.json" "$cycles" <<'PY' || fail "/api/state"
import json, sys, time, urllib.request
def state():
    with urllib.request.urlopen(sys.argv[1] + "/api/state", timeout=5) as r:
        return json.load(r)["blmc"]
# After the run the page goes on with the board's status frames (one a second): disabled.
end = time.monotonic() + 5
while state()["boards"][0]["flags"]["system_enabled"] and time.monotonic() < end:
    time.sleep(0.1)
state = state()
info = json.load(open(sys.argv[2]))
board = state["boards"][0]
n, t = board["samples"]["n"], board["samples"]["t"]
# 50 a second: about 100 in 2 s, fewer when a loaded machine held the loop up (no cycles, no samples).
assert 10 <= n <= 110 and len(t) == n == len(board["samples"]["p1"]), "%d samples of a 2 s run at 50 Hz" % n
slots = [int((x + 1e-6) / 0.02) for x in t]  # at most one sample in each 20 ms of the loop's time
assert all(a < b for a, b in zip(slots, slots[1:])), "two samples within 20 ms: %s" % t
assert state["loop"]["cycles"] == int(sys.argv[3]), state["loop"]
assert board["flags"]["system_enabled"] is False, board["flags"]
assert board["error"]["name"] == "NONE", board["error"]
assert info["boards"][0]["limits"]["max_current_a"] == 1.5, info["boards"][0]
PY
get() { curl -sSf "$URL$1" >"$TMP/body" || fail "GET $1"; }
get / && grep -q 'href="/blmc.html"' "$TMP/body" || fail "the index does not list the blmc page"
get /blmc.html && grep -q 'src="/javascript/chart.js/chart.min.js"' "$TMP/body" || fail "/blmc.html is not the page"
get /blmc.js
if [ -f /usr/share/javascript/chart.js/chart.min.js ]; then
  get /javascript/chart.js/chart.min.js && grep -q 'Chart.js' "$TMP/body" || fail "Chart.js not served"
fi
echo PASS
