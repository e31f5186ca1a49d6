#!/usr/bin/env bash
# `axon sim fps` serves six simulated positioners as a CAN@net gateway; separate `axon fps`
# processes discover them, read the status table as JSON, move one, run a trajectory, and get a
# clear error for a robot that does not exist.
source "$(dirname "$0")/lib.sh"
start_sim_fps --robots 1-6 --gateway 127.0.0.1:0 --time-scale 20
fps() { "$AXON" fps --gateway "127.0.0.1:$SIM_CANNET_PORT" "$@"; }

fps discover >"$TMP/discover.out" 2>"$TMP/discover.err" || fail "discover exited with $?"
grep -Eq ': 6 robots: 1 2 3 4 5 6$' "$TMP/discover.out" || fail "discover did not list robots 1-6"

fps status --json >"$TMP/status.out" 2>"$TMP/status.err" || fail "status exited with $?"
/usr/bin/python3 - "$TMP/status.out" <<'PY' || fail "status --json is not what was expected"
import json, sys
j = json.load(open(sys.argv[1]))
ids = [r["id"] for r in j["robots"]]
assert ids == [1, 2, 3, 4, 5, 6], ids
assert all(r["ready"] and r["state"] == "ready" for r in j["robots"]), j["robots"]
assert all("DATUM_ALPHA_INITIALIZED" in r["flags"] for r in j["robots"])
assert j["ready"] == 6
PY

fps goto 3 30 150 >"$TMP/goto.out" 2>"$TMP/goto.err" || fail "goto exited with $?"
fps --json position 3 >"$TMP/position.out" 2>"$TMP/position.err" || fail "position exited with $?"
/usr/bin/python3 - "$TMP/position.out" <<'PY' || fail "robot 3 is not at 30/150"
import json, sys
p = json.load(open(sys.argv[1]))["3"]
assert abs(p["alpha"] - 30) <= 0.1 and abs(p["beta"] - 150) <= 0.1, p
PY

cat >"$TMP/traj.yaml" <<'YAML'
1: {alpha: [[10, 1.0], [20, 2.0]], beta: [[175, 1.0]]}
2: {alpha: [[15, 1.5]]}
YAML
fps move --trajectory "$TMP/traj.yaml" >"$TMP/move.out" 2>"$TMP/move.err" || fail "move exited with $?"
fps --json position 1,2 >"$TMP/pos12.out" 2>"$TMP/pos12.err" || fail "position 1,2 exited with $?"
/usr/bin/python3 - "$TMP/pos12.out" <<'PY' || fail "trajectory did not end at its last points"
import json, sys
j = json.load(open(sys.argv[1]))
assert abs(j["1"]["alpha"] - 20) <= 0.1 and abs(j["1"]["beta"] - 175) <= 0.1, j
assert abs(j["2"]["alpha"] - 15) <= 0.1 and abs(j["2"]["beta"] - 180) <= 0.1, j
PY

# A robot nobody has: exit 1 and a message naming it.
if fps goto 99 10 10 >"$TMP/bad.out" 2>"$TMP/bad.err"; then fail "goto 99 succeeded"; else rc=$?; fi
[ "$rc" = 1 ] || fail "goto 99 exited with $rc, expected 1"
grep -q '99' "$TMP/bad.err" || fail "the error does not name robot 99"

# A move the firmware refuses (beyond the hard stop): the response code name reaches the user.
if fps goto 3 400 180 >"$TMP/far.out" 2>"$TMP/far.err"; then fail "goto beyond the stop succeeded"; else rc=$?; fi
[ "$rc" = 1 ] || fail "goto beyond the stop exited with $rc"
grep -Eq 'VALUE_OUT_OF_RANGE|out of range' "$TMP/far.err" || fail "no response code in: $(cat "$TMP/far.err")"
# A trajectory (JSON this time) the firmware refuses, too fast: exit 1, nothing starts, robot 4 named.
echo '{"4": {"alpha": [[300, 0.5]]}}' >"$TMP/fast.json"
if fps --json move --trajectory "$TMP/fast.json" >"$TMP/fast.out" 2>"$TMP/fast.err"; then fail "too-fast trajectory succeeded"; fi
/usr/bin/python3 - "$TMP/fast.out" <<'PY' || fail "too-fast trajectory report is not what was expected"
import json, sys
j = json.load(open(sys.argv[1]))
assert not j["started"], j
r = j["robots"][0]
assert r["id"] == 4 and r["state"] == "upload-failed", r
assert "VALUE_OUT_OF_RANGE" in r["detail"], r
PY
fps --json position 4 >"$TMP/pos4.out" 2>"$TMP/pos4.err" || fail "position 4 exited with $?"
/usr/bin/python3 -c 'import json,sys; p=json.load(open(sys.argv[1]))["4"]; assert abs(p["alpha"])<=0.1, p' "$TMP/pos4.out" ||
  fail "robot 4 moved after a refused trajectory"

# Ctrl-C: the simulator stops and sums up.
kill -INT "$SIM_PID"
wait "$SIM_PID" || fail "axon sim fps exited with $? after SIGINT"
grep -Eq 'frames processed, .* 0 receive overflows, 0 collisions' "$TMP/sim.err" || fail "no summary from the simulator"
echo "PASS"
