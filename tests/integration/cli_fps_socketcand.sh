#!/usr/bin/env bash
# `axon sim fps` over socketcand with the robots on two buses; `axon fps` finds them on both and
# moves one robot of the second bus.
source "$(dirname "$0")/lib.sh"
start_sim_fps --robots 1-4 --buses 2 --socketcand 127.0.0.1:0 --time-scale 20
fps() { "$AXON" fps --socketcand "127.0.0.1:$SIM_SCD_PORT" --channel can0 --channel can1 "$@"; }

fps --json discover >"$TMP/discover.out" 2>"$TMP/discover.err" || fail "discover exited with $?"
/usr/bin/python3 - "$TMP/discover.out" <<'PY' || fail "discover did not find 1,2 on can0 and 3,4 on can1"
import json, sys
j = json.load(open(sys.argv[1]))
buses = {b["name"].split("/")[-1]: b["robots"] for b in j["buses"]}
assert sorted(buses.values()) == [[1, 2], [3, 4]], buses
PY
fps goto 4 90 170 >"$TMP/goto.out" 2>"$TMP/goto.err" || fail "goto exited with $?"
grep -q 'robot 4 at alpha 90.0' "$TMP/goto.out" || fail "goto output: $(cat "$TMP/goto.out")"
fps raw 4 GET_FIRMWARE_VERSION >"$TMP/raw.out" 2>"$TMP/raw.err" || fail "raw exited with $?"
grep -q 'ACCEPTED\|accepted' "$TMP/raw.out" || fail "raw output: $(cat "$TMP/raw.out")"
echo "PASS"
