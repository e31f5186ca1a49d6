#!/usr/bin/env bash
# `axon sim plc` serves the PLC register map over Modbus TCP; separate `axon fps plc` processes read
# the status, switch a sextant's power and a gateway off, pulse the sync line (the emulator logs
# every relay change), read the cold policy from scripted temperatures, and get a typed error from
# a port where nothing listens.
source "$(dirname "$0")/lib.sh"

cat >"$TMP/script.yaml" <<'YAML'
- {t: 0, sensor: fps_plate_centre, value: -12.5}
- {t: 0, sensor: humidity, value: 55}
YAML
"$AXON" sim plc --listen 127.0.0.1:0 --script "$TMP/script.yaml" >"$TMP/plc.out" 2>"$TMP/plc.err" &
PIDS+=($!)
PLC_PORT=$(wait_for_line "$TMP/plc.out" '^listening plc ' | sed 's/.*://')
plc() { "$AXON" fps plc "$@" --host "127.0.0.1:$PLC_PORT"; }

plc status >"$TMP/status.out" 2>"$TMP/status.err" || fail "status exited with $?"
grep -Eq '^positioner power +on +on +on +on +on +on$' "$TMP/status.out" || fail "status: positioner power not all on"
grep -Eq '^sync line +low$' "$TMP/status.out" || fail "status: sync line not low"
grep -Eq '^fps_plate_centre +-12.50 degC$' "$TMP/status.out" || fail "status: scripted temperature missing"

plc power 3 off >"$TMP/power.out" 2>"$TMP/power.err" || fail "power exited with $?"
grep -q '^positioner power 3 off$' "$TMP/power.out" || fail "power did not report sextant 3 off"
plc gateway 5 off >"$TMP/gw.out" 2>"$TMP/gw.err" || fail "gateway exited with $?"
plc --json status >"$TMP/status.json" 2>"$TMP/status.err" || fail "status --json exited with $?"
/usr/bin/python3 - "$TMP/status.json" <<'PY' || fail "status --json is not what was expected"
import json, sys
j = json.load(open(sys.argv[1]))
assert j["positioner_power"] == [True, True, False, True, True, True], j["positioner_power"]
assert j["gateway_power"] == [True, True, True, True, False, True], j["gateway_power"]
assert j["sync_line"] is False
assert abs(j["humidity"]["value"] - 55) < 1e-6, j["humidity"]
assert len(j["temperatures"]) == 6
PY

plc sync pulse --hold 0.05 >"$TMP/sync.out" 2>"$TMP/sync.err" || fail "sync pulse exited with $?"
grep -q '^sync line low$' "$TMP/sync.out" || fail "sync pulse did not end low"
wait_for_line "$TMP/plc.err" 'plc emulator: client 127\.0\.0\.1:[0-9]+ switched positioner power 3 off' >/dev/null
wait_for_line "$TMP/plc.err" 'plc emulator: client 127\.0\.0\.1:[0-9]+ switched gateway power 5 off' >/dev/null
wait_for_line "$TMP/plc.err" 'plc emulator: client 127\.0\.0\.1:[0-9]+ switched sync line high' >/dev/null
wait_for_line "$TMP/plc.err" 'plc emulator: client 127\.0\.0\.1:[0-9]+ switched sync line low' >/dev/null

plc --json cold >"$TMP/cold.json" 2>"$TMP/cold.err" || fail "cold exited with $?"
/usr/bin/python3 - "$TMP/cold.json" <<'PY' || fail "cold policy is not what -12.5 degC calls for"
import json, sys
j = json.load(open(sys.argv[1]))
assert j["speed_limited"] and j["heating"], j
assert j["motor_rpm"] == 3000 and j["alpha_holding_pct"] == 45 and j["beta_holding_pct"] == 30, j
assert j["coldest_sensor"] == "fps_plate_centre", j
PY

# Nothing listens on the port of a stopped emulator.
"$AXON" sim plc --listen 127.0.0.1:0 --duration 0.1 >"$TMP/short.out" 2>"$TMP/short.err" || fail "short sim failed"
DEAD_PORT=$(sed -n 's/^listening plc .*://p' "$TMP/short.out")
if "$AXON" fps plc status --host "127.0.0.1:$DEAD_PORT" --plc-timeout 0.5 >"$TMP/dead.out" 2>"$TMP/dead.err"; then
  fail "status against a dead port succeeded"
fi
grep -q 'cannot connect to the PLC' "$TMP/dead.err" || fail "no connect error for a dead port"
echo "PASS"
