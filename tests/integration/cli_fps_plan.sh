#!/usr/bin/env bash
# Path planning on the command line: `fps plan` on the default 500-robot layout writes a verified
# plan.json, `fps plot` draws it, targets outside the safe zone are reported; `fps goto-all` plans from the simulated benchtop robots' positions,
# runs the move and reports every robot completed at its target.
source "$(dirname "$0")/lib.sh"
DATA="$(cd "$(dirname "$0")/../../data/layouts" && pwd)"

"$AXON" fps plan --layout "$DATA/default.yaml" --to random --seed 5 -o "$TMP/plan.json" --svg "$TMP/plan.svg" \
  --allow-partial 2>"$TMP/plan.err" || fail "plan exited with $? ($(cat "$TMP/plan.err"))"
grep -q 'verified by the checker' "$TMP/plan.err" || fail "plan: not verified: $(cat "$TMP/plan.err")"
/usr/bin/python3 - "$TMP/plan.json" <<'PY' || fail "plan.json is not what was expected"
import json, sys
j = json.load(open(sys.argv[1]))
assert j["format"] == "axon-fps-plan" and j["verified"] is True, j.get("verified")
assert len(j["robots"]) == 500
st = j["stats"]
assert st["checks"] >= 1 and st["smooth_s"] >= 0 and st["max_points"] <= 1023, st
for r in j["robots"]:
    for arm in ("alpha", "beta"):
        pts = r[arm]
        assert pts[0][1] == 0 and len(pts) - 1 <= 1023
        for (a0, t0), (a1, t1) in zip(pts, pts[1:]):
            assert t1 > t0 and abs(a1 - a0) / (t1 - t0) <= 12 + 1e-6, (r["id"], arm)
    if r["status"] in ("parked", "held"):
        assert r["reason"], r
PY
grep -q '<svg' "$TMP/plan.svg" || fail "plan --svg wrote no SVG"
"$AXON" fps plot --layout "$DATA/default.yaml" --plan "$TMP/plan.json" --at 5 -o "$TMP/at5.svg" 2>"$TMP/plot.err" \
  || fail "plot of the plan at 5 s exited with $? ($(cat "$TMP/plot.err"))"
grep -q 'at 5.00 s' "$TMP/at5.svg" || fail "plot: title"

# --json: the plan document alone on stdout (the summary on stderr); with -o FILE it is a usage error.
"$AXON" fps plan --layout "$DATA/benchtop.yaml" --to random --seed 2 --json >"$TMP/plan-json.out" 2>"$TMP/plan-json.err" \
  || fail "plan --json exited $?"
/usr/bin/python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); assert d["format"] == "axon-fps-plan", d.keys()' \
  "$TMP/plan-json.out" || fail "plan --json: stdout is not the plan alone: $(head -c 300 "$TMP/plan-json.out")"
grep -q '^plan: ' "$TMP/plan-json.err" || fail "plan --json: summary not on stderr"
rc=0; "$AXON" fps plan --layout "$DATA/benchtop.yaml" --to random --json -o "$TMP/x.json" 2>/dev/null || rc=$?
[ "$rc" = 2 ] || fail "plan --json -o FILE: exit $rc, expected 2"

# A directory of calibration tables is a layout: the robots' own geometry and the guide cameras.
CAL="$(cd "$(dirname "$0")/../fps/data/calibration" && pwd)"
"$AXON" fps plan --layout "$CAL" --to random --seed 3 --allow-partial 2>"$TMP/cal.err" \
  || fail "plan on calibration tables exited with $? ($(cat "$TMP/cal.err"))"
grep -q '^plan: 6 robots' "$TMP/cal.err" && grep -q 'verified by the checker' "$TMP/cal.err" \
  || fail "plan on calibration tables: $(cat "$TMP/cal.err")"

# A target file with a typo'd robot is an error, not a silent drop.
printf 'targets:\n  - {robot: 99, alpha: 10, beta: 170}\n' >"$TMP/bad.yaml"
if "$AXON" fps plan --layout "$DATA/benchtop.yaml" --to "$TMP/bad.yaml" 2>"$TMP/bad.err"; then fail "unknown robot accepted"; fi
grep -q '99' "$TMP/bad.err" || fail "unknown robot not named: $(cat "$TMP/bad.err")"

# A boss target 0.1 mm inside robot 1's reach plans, but leaves the safe zone (spec section 11):
# a robot with arms at the tolerance could not reach it, and the summary says by how much.
printf 'targets:\n  - {robot: 1, x: -22.3, y: 0, fibre: boss}\n' >"$TMP/edge.yaml"
"$AXON" fps plan --layout "$DATA/benchtop.yaml" --to "$TMP/edge.yaml" 2>"$TMP/edge.err" \
  || fail "plan of a target near the reach exited with $? ($(cat "$TMP/edge.err"))"
grep -q 'safe zone (spec section 11): the targets of 1 robots leave it' "$TMP/edge.err" \
  && grep -q 'robot 1: target 0.14[0-9] mm beyond' "$TMP/edge.err" || fail "safe zone not reported: $(cat "$TMP/edge.err")"

# goto-all on the simulated benchtop (robots start folded at alpha 0, beta 180).
cat >"$TMP/targets.yaml" <<'YAML'
targets:
  - {robot: 1, alpha: 30, beta: 150}
  - {robot: 2, alpha: 90, beta: 140}
  - {robot: 3, alpha: 200, beta: 160}
  - {robot: 4, alpha: 10, beta: 170}
  - {robot: 5, alpha: 300, beta: 150}
  - {robot: 6, alpha: 45, beta: 175}
YAML
start_sim_fps --robots 1-6 --gateway 127.0.0.1:0
"$AXON" fps --gateway "127.0.0.1:$SIM_CANNET_PORT" goto-all --layout "$DATA/benchtop.yaml" --targets "$TMP/targets.yaml" \
  --save-plan "$TMP/bench_plan.json" >"$TMP/goto.out" 2>"$TMP/goto.err" \
  || fail "goto-all exited with $?: $(cat "$TMP/goto.out" "$TMP/goto.err")"
grep -qi 'completed' "$TMP/goto.out" || fail "goto-all: $(cat "$TMP/goto.out")"
"$AXON" fps --gateway "127.0.0.1:$SIM_CANNET_PORT" --json position 2>/dev/null >"$TMP/pos.json" || fail "position"
/usr/bin/python3 - "$TMP/pos.json" <<'PY' || fail "robots are not at their targets: $(cat "$TMP/pos.json")"
import json, sys
want = {1: (30, 150), 2: (90, 140), 3: (200, 160), 4: (10, 170), 5: (300, 150), 6: (45, 175)}
j = json.load(open(sys.argv[1]))
got = {int(k): (v["alpha"], v["beta"]) for k, v in j.items()}
for i, (a, b) in want.items():
    assert abs(got[i][0] - a) < 0.2 and abs(got[i][1] - b) < 0.2, (i, got[i])
PY
echo "ok"
