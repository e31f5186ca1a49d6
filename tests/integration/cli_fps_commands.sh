#!/usr/bin/env bash
# One simulated positioner alone (no neighbours, so calibration cannot hit anything) behind a
# CAN@net emulator: `axon fps` datum, calibrate, stop and unlock each succeed and leave the robot
# ready; a --config file selects the gateway, and a file with an unknown key is refused with its
# file and line.
source "$(dirname "$0")/lib.sh"
start_sim_fps --robots 1 --gateway 127.0.0.1:0 --time-scale 50
fps() { "$AXON" fps --gateway "127.0.0.1:$SIM_CANNET_PORT" --timeout 2 "$@"; }

# status --json of robot 1 must say ready.
expect_ready() {
  "$AXON" fps "$@" --json status >"$TMP/status.out" 2>"$TMP/status.err" || fail "status exited with $? ($*)"
  /usr/bin/python3 - "$TMP/status.out" <<'PY' || fail "robot 1 is not ready: $(cat "$TMP/status.out")"
import json, sys
j = json.load(open(sys.argv[1]))
assert [r["id"] for r in j["robots"]] == [1], j
assert j["robots"][0]["ready"] and j["robots"][0]["state"] == "ready", j["robots"][0]
PY
}
gw=(--gateway "127.0.0.1:$SIM_CANNET_PORT" --timeout 2)

fps datum 1 >"$TMP/datum.out" 2>"$TMP/datum.err" || fail "datum exited with $?: $(cat "$TMP/datum.err")"
expect_ready "${gw[@]}"
fps calibrate 1 --motor --datum --save >"$TMP/cal.out" 2>"$TMP/cal.err" ||
  fail "calibrate exited with $?: $(cat "$TMP/cal.err")"
expect_ready "${gw[@]}"
fps stop >"$TMP/stop.out" 2>"$TMP/stop.err" || fail "stop exited with $?: $(cat "$TMP/stop.err")"
expect_ready "${gw[@]}"
fps unlock >"$TMP/unlock.out" 2>"$TMP/unlock.err" || fail "unlock exited with $?: $(cat "$TMP/unlock.err")"
grep -q '1 robots acknowledged, 0 silent' "$TMP/unlock.out" || fail "unlock output: $(cat "$TMP/unlock.out")"
expect_ready "${gw[@]}"

# The same gateway chosen by a --config file.
cat >"$TMP/buses.yaml" <<YAML
gateway: 127.0.0.1:$SIM_CANNET_PORT
channels: [1]
timeout_ms: 2000
YAML
expect_ready --config "$TMP/buses.yaml"

# Not a terminal: no colour codes in the text table.
"$AXON" fps --config "$TMP/buses.yaml" status >"$TMP/text.out" 2>"$TMP/text.err" || fail "text status exited with $?"
grep -q '1 robots, 1 ready' "$TMP/text.out" || fail "text status: $(cat "$TMP/text.out")"
if grep -q $'\x1b\[' "$TMP/text.out"; then fail "colour codes written to a file"; fi

# An unknown key: refused, with the file and line of the key.
cat >"$TMP/bad.yaml" <<YAML
gateway: 127.0.0.1:$SIM_CANNET_PORT
chanels: [1]
YAML
if "$AXON" fps --config "$TMP/bad.yaml" status >"$TMP/bad.out" 2>"$TMP/bad.err"; then fail "a config with an unknown key was accepted"; fi
grep -q "bad.yaml:2" "$TMP/bad.err" || fail "the error does not locate the key: $(cat "$TMP/bad.err")"
grep -q "chanels" "$TMP/bad.err" || fail "the error does not name the key: $(cat "$TMP/bad.err")"

kill -INT "$SIM_PID"
wait "$SIM_PID" || fail "axon sim fps exited with $? after SIGINT"
grep -Eq '0 collisions' "$TMP/sim.err" || fail "the robot collided: $(tail -3 "$TMP/sim.err")"
echo "PASS"
