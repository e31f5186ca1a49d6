#!/usr/bin/env bash
# `axon fps plane friction` and `halltest` between processes (interface document 9.4.2, 9.4.3),
# against a simulated plane whose scenario gives robot 1's beta arm extra friction (level 10, below
# the beta collision margin: no false collisions) and robot 3's alpha a stuck hall sensor:
#  1. a history file written by hand holds robot 1's healthy fit from last year (15 % + 5 %/krpm);
#     the survey of robots 1 and 2 finds robot 1's beta increased (exit 1), every other arm a new
#     baseline, and appends four records;
#  2. the survey again with --json: robot 2 now ok against its baseline, robot 1 beta still up;
#  3. halltest 3: alpha no_hall_change, beta ok, exit 1; every arm back in closed loop;
#  4. halltest 2 --arm beta --json: ok, exit 0;
#  5. halltest 99: refused with a clear error; a bad history line: refused naming the line.
source "$(dirname "$0")/lib.sh"

cat >"$TMP/faults.yaml" <<'EOF'
friction: [{id: 1, arm: beta, level: 10}]
hall: [{id: 3, arm: alpha, fault: stuck}]
EOF
start_plane a "$SMALL_PLANE" --scenario "$TMP/faults.yaml"
plane() { "$AXON" fps plane --layout "$TMP/a.yaml" "$@"; }
speeds="--speeds 500,1000,1500"  # long enough moves for several readings each at time x20

cat >"$TMP/history.csv" <<'EOF'
time_utc,robot,arm,stiction_percent,viscous_percent_per_krpm,rms_percent,move_ratio
2025-12-01T10:00:00Z,1,beta,15.000,5.0000,0.100,0
EOF
plane friction 1,2 --history "$TMP/history.csv" $speeds >"$TMP/f1.out" 2>"$TMP/f1.err" && fail "the stiff arm passed"
cat "$TMP/f1.out"
grep -Eq '^robot 1 beta: increased, stiction [0-9.]+ % \+ [0-9.]+ %/krpm .*since 2025-12-01T10:00:00Z' "$TMP/f1.out" ||
  fail "robot 1 beta not found increased"
grep -q 'SET_COLLISION_MARGIN, 111' "$TMP/f1.out" || fail "no advice"
for arm in "1 alpha" "2 alpha" "2 beta"; do
  grep -q "^robot $arm: baseline" "$TMP/f1.out" || fail "robot $arm not a baseline"
done
[ "$(wc -l <"$TMP/history.csv")" = 6 ] || fail "four records not appended: $(cat "$TMP/history.csv")"

plane friction 1,2 --history "$TMP/history.csv" $speeds --json >"$TMP/f2.out" 2>"$TMP/f2.err" && fail "second survey passed"
/usr/bin/python3 - "$TMP/f2.out" <<'PY' || fail "the friction JSON"
import json, sys
r = json.load(open(sys.argv[1]))
v = {(a["id"], a["arm"]): a for a in r["arms"]}
assert r["ok"] is False, r
assert v[(2, "alpha")]["verdict"] == "ok" and v[(2, "beta")]["verdict"] == "ok", v
assert v[(1, "beta")]["verdict"] == "increased" and v[(1, "beta")]["growth"] > 0.4, v[(1, "beta")]
assert v[(1, "beta")]["baseline_time_utc"] == "2025-12-01T10:00:00Z"
f = v[(2, "alpha")]["fit"]
assert abs(f["stiction_percent"] - 15) < 2 and abs(f["viscous_percent_per_krpm"] - 5) < 1, f
assert all(p["readings"] > 0 for p in v[(2, "alpha")]["points"])
PY

plane halltest 3 >"$TMP/h1.out" 2>"$TMP/h1.err" && fail "the stuck sensor passed"
cat "$TMP/h1.out"
grep -q '^robot 3 alpha: no_hall_change' "$TMP/h1.out" || fail "the stuck sensor was not found"
grep -q '^robot 3 beta: ok' "$TMP/h1.out" || fail "the healthy arm was not ok"
grep -q 'NOT restored' "$TMP/h1.out" && fail "an arm was left in open loop"

plane halltest 2 --arm beta --json >"$TMP/h2.out" 2>"$TMP/h2.err" || fail "halltest 2: $(cat "$TMP/h2.err")"
/usr/bin/python3 - "$TMP/h2.out" <<'PY' || fail "the hall JSON"
import json, sys
r = json.load(open(sys.argv[1]))
assert r["ok"] is True and len(r["arms"]) == 1, r
a = r["arms"][0]
assert a["arm"] == "beta" and a["verdict"] == "ok" and a["restored"] and a["tracking_error_deg"] <= 0.04, a
PY

plane halltest 99 >"$TMP/h3.out" 2>"$TMP/h3.err" && fail "robot 99 accepted"
grep -q "robot 99 is not in the layout" "$TMP/h3.err" || fail "no clear error for robot 99: $(cat "$TMP/h3.err")"
echo "2025-12-01T10:00:00Z,1,gamma,1,2,3,4" >>"$TMP/history.csv"
plane friction 2 --history "$TMP/history.csv" >"$TMP/f3.out" 2>"$TMP/f3.err" && fail "a bad history line was read"
grep -q "history.csv:11:" "$TMP/f3.err" || fail "the bad line was not named: $(cat "$TMP/f3.err")"
echo PASS
