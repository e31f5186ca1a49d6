#!/usr/bin/env bash
# `axon blmc --json` against `axon sim blmc` in another process: stdout carries JSON Lines only (one
# object per line, each with a type), logs stay on stderr; the motion commands end with a report
# (loop cycles, jitter, overruns, tracking error, fault, disabled, exit code), also after a safety
# stop. And `axon sim blmc` with no options serves on 127.0.0.1:29536, as the docs show.
source "$(dirname "$0")/lib.sh"
"$AXON" sim blmc --socketcand 127.0.0.1:0 >"$TMP/sim.out" 2>"$TMP/sim.err" &
PIDS+=($!)
PORT=$(wait_for_line "$TMP/sim.out" '^listening socketcand ' | sed 's/.*://')
blmc() { "$AXON" blmc --socketcand "127.0.0.1:$PORT/can0" --no-realtime --json "$@"; }

# check_json FILE PYTHON: every line of FILE is a JSON object with a type; PYTHON then asserts on
# `lines` (the parsed objects).
check_json() {
  /usr/bin/python3 - "$1" "$2" <<'PY' || fail "$1: $(head -c 2000 "$1")"
import json, sys
lines = []
for n, text in enumerate(open(sys.argv[1]), 1):
    obj = json.loads(text)
    assert isinstance(obj, dict) and "type" in obj, f"line {n}: {text!r}"
    lines.append(obj)
exec(sys.argv[2])
PY
}

blmc status >"$TMP/status.out" 2>"$TMP/status.err" || fail "status failed"
check_json "$TMP/status.out" '
assert len(lines) == 1 and lines[0]["type"] == "status", lines
s = lines[0]
assert s["system_enabled"] is False and s["error"] == "NONE" and s["byte"] == 0, s'

blmc --stale-ms 500 pd --amplitude 0.2 --frequency 1 --duration 2 >"$TMP/pd.out" 2>"$TMP/pd.err" || fail "pd failed: $(cat "$TMP/pd.err")"
check_json "$TMP/pd.out" '
samples = [l for l in lines if l["type"] == "sample"]
assert len(samples) >= 5, len(samples)
assert all(len(s["position"]) == 2 and len(s["current"]) == 2 for s in samples)
r = lines[-1]
assert r["type"] == "report" and r["command"] == "pd", r
assert r["enabled"] and r["disabled"] and r["exit_code"] == 0 and r["fault"] is None and r["stopped_by"] is None, r
assert r["loop"]["cycles"] > 1000 and r["loop"]["period_nominal_us"] == 1000, r["loop"]
for k in ("jitter_p99_us", "jitter_max_us", "overruns", "missed", "period_mean_us"):
    assert k in r["loop"], k
assert [t["motor"] for t in r["tracking"]] == [1, 2], r["tracking"]
assert all(t["samples"] > 0 and t["rms_rev"] < 0.1 for t in r["tracking"]), r["tracking"]'
grep -q 'cycles, period' "$TMP/pd.err" || fail "the loop's log line left stderr"

# A safety stop (a 0.05 ms stale limit trips at once): exit 4, the fault in the report, board off.
set +e
blmc --stale-ms 0.05 current 1 0.2 --duration 5 >"$TMP/fault.out" 2>"$TMP/fault.err"
rc=$?
set -e
[ "$rc" = 4 ] || fail "safety stop exited $rc, expected 4: $(cat "$TMP/fault.err")"
check_json "$TMP/fault.out" '
r = lines[-1]
assert r["type"] == "report" and r["fault"]["kind"] == "stale data" and "stale data" in r["fault"]["text"], r
assert r["disabled"] and r["exit_code"] == 4, r'

blmc raw ENABLE_SYS=0 >"$TMP/raw.out" 2>"$TMP/raw.err" || fail "raw failed"
check_json "$TMP/raw.out" '
assert lines == [{"type": "sent", "frame": "000#0000000000000001", "decoded": "COMMAND ENABLE_SYS=0"}], lines'

blmc monitor --duration 0.5 >"$TMP/monitor.out" 2>"$TMP/monitor.err" || fail "monitor failed"
check_json "$TMP/monitor.out" 'assert lines and all(l["type"] == "sample" for l in lines), lines'

# Without --json: the table, then the tracking lines.
"$AXON" blmc --socketcand "127.0.0.1:$PORT/can0" --no-realtime --stale-ms 500 pd --duration 1 >"$TMP/pd.txt" 2>/dev/null \
  || fail "pd (text) failed"
head -1 "$TMP/pd.txt" | grep -q '^ *t\[s\] |' || fail "no table header: $(head -1 "$TMP/pd.txt")"
grep -q '^motor 1: tracking error rms' "$TMP/pd.txt" || fail "no tracking line: $(tail -2 "$TMP/pd.txt")"

# The default address. Another test or program may hold the port: then only that part is skipped.
"$AXON" sim blmc >"$TMP/default.out" 2>"$TMP/default.err" &
DEF=$!
PIDS+=($DEF)
for _ in $(seq 100); do
  grep -q '^listening' "$TMP/default.out" 2>/dev/null && break
  kill -0 "$DEF" 2>/dev/null || break
  sleep 0.05
done
if grep -q '^listening socketcand 127.0.0.1:29536$' "$TMP/default.out"; then
  "$AXON" blmc --socketcand 127.0.0.1:29536/can0 status >"$TMP/readme.out" 2>"$TMP/readme.err" \
    || fail "the documented status example failed: $(cat "$TMP/readme.err")"
  grep -q '^sys-off ' "$TMP/readme.out" || fail "status: $(cat "$TMP/readme.out")"
elif grep -qi 'in use' "$TMP/default.err"; then
  echo "SKIP: 127.0.0.1:29536 is in use; the default address was not tried"
else
  fail "axon sim blmc without options: $(cat "$TMP/default.err")"
fi
echo "PASS"
