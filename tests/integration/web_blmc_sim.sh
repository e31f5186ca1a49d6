#!/usr/bin/env bash
# `axon sim blmc --http 127.0.0.1:0`: the simulated board's own truth on the blmc page while a host
# drives it over socketcand (`axon blmc current`, another process):
#   1. /api/blmc/state follows the simulator: samples at 50 Hz, the motor's current at what the host
#      asked for, its velocity and position moving, the board enabled during the run and disabled
#      after it (the host disables it at its end);
#   2. /metrics passes `promtool check metrics` and has the board's families.
source "$(dirname "$0")/lib.sh"
command -v promtool >/dev/null || fail "promtool not found (Debian's prometheus package; scripts/install-deps.sh)"

printf 'alignment_s: 0.2\n' >"$TMP/board.yaml"
"$AXON" sim blmc --socketcand 127.0.0.1:0 --config "$TMP/board.yaml" --no-realtime --http 127.0.0.1:0 \
  >"$TMP/sim.out" 2>"$TMP/sim.err" &
PIDS+=($!)
PORT=$(wait_for_line "$TMP/sim.out" '^listening socketcand ' | sed 's/.*://')
URL=http://$(wait_for_line "$TMP/sim.out" '^listening http ' | awk '{print $3}')

# Generous stale and receive limits: a loaded machine must not end the run in a safety stop.
"$AXON" blmc --socketcand "127.0.0.1:$PORT/can0" --no-realtime --stale-ms 1000 --recv-timeout-ms 0 \
  current 1 0.3 --duration 3 >"$TMP/current.out" 2>"$TMP/current.err" &
HOST_PID=$!
PIDS+=($HOST_PID)

/usr/bin/python3 - "$URL" <<'PY' || fail "/api/blmc/state does not follow the simulated board"
import json, sys, time, urllib.request
def state():
    with urllib.request.urlopen(sys.argv[1] + "/api/blmc/state", timeout=5) as r:
        return json.load(r)
# During the run: the board enabled, motor 1 at the host's 0.3 A and turning.
end, seen = time.monotonic() + 30, None
while time.monotonic() < end:
    s = state()
    b = s["boards"][0]
    if b["flags"]["system_enabled"] and b["samples"]["n"] > 5 and max(map(abs, b["samples"]["v1"])) > 0.01:
        seen = b
        break
    time.sleep(0.1)
assert seen, "the page never showed the board enabled and motor 1 turning: %s" % json.dumps(b)[:800]
s = seen["samples"]
assert abs(s["i1"][-1] - 0.3) < 0.02, "motor 1 current %s A, the host asked for 0.3 A" % s["i1"][-1]
assert abs(s["i2"][-1]) < 1e-9, "motor 2 has current %s A without a command" % s["i2"][-1]
assert s["n"] == len(s["t"]) == len(s["p1"]) == len(s["v1"]), s
slots = [int((x + 1e-6) / 0.02) for x in s["t"]]  # at most one sample in each 20 ms
assert all(a < b for a, b in zip(slots, slots[1:])), "two samples within 20 ms: %s" % s["t"]
assert s["p1"][-1] != s["p1"][0], "motor 1 did not move: %s" % s["p1"]
# After the run the host disables the board: the simulator shows it.
end = time.monotonic() + 30
while state()["boards"][0]["flags"]["system_enabled"] and time.monotonic() < end:
    time.sleep(0.1)
b = state()["boards"][0]
assert not b["flags"]["system_enabled"], b["flags"]
assert abs(b["samples"]["i1"][-1]) < 1e-9, "current %s A after the host disabled the board" % b["samples"]["i1"][-1]
print("page: motor 1 at %.3f A, %.2f krpm during the run; disabled after it" % (s["i1"][-1], max(map(abs, s["v1"]))))
PY
wait "$HOST_PID" || fail "axon blmc current failed"

curl -sSf "$URL/metrics" >"$TMP/metrics.txt" || fail "GET /metrics"
promtool check metrics <"$TMP/metrics.txt" >"$TMP/promtool.out" 2>&1 || { cat "$TMP/promtool.out" >&2; fail "promtool check metrics"; }
for name in axon_blmc_current_amperes axon_blmc_position_revolutions axon_blmc_velocity_revolutions_per_second \
            axon_blmc_status_flag axon_blmc_error_code axon_blmc_board_errors_total axon_web_http_requests_total; do
  grep -q "^# TYPE $name " "$TMP/metrics.txt" || fail "no $name in /metrics"
done
curl -sSf "$URL/" | grep -q 'href="/blmc.html"' || fail "the index does not list the blmc page"
echo PASS
