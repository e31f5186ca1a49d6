#!/usr/bin/env bash
# Correction iterations between processes: `axon sim fps --layout` (CAN@net emulators + PLC) and
# `axon fps plane correct`. The "camera" is python: it puts the angles the robots were commanded
# through the nominal kinematics (alpha arm 7.4 mm, boss fibre at (14.997, -0.375) mm on the beta
# arm, orientation 0), the simulated robots having no zero errors.
#  1. every robot is moved to (30, 150) with `fps plane move`;
#  2. targets: (31, 148.5) for five robots, where robot 9 already is (+2 um) for the sixth;
#  3. `correct` reads measurement 1 (the fibres at (30, 150)), corrects five robots, leaves robot 9,
#     then waits for measurement 2, which python writes from the commands `correct` printed;
#  4. measurement 2 is within 5 um everywhere: exit 0; the robots read back (31, 148.5);
#  5. a measurement naming a robot that is not in the layout is refused with file:line.
source "$(dirname "$0")/lib.sh"
PY=/usr/bin/python3

cat >"$TMP/camera.py" <<'EOF2'
# camera.py OUT ROBOT:ALPHA:BETA[:DX_UM] ...  writes robot,x,y (mm) of each robot's boss fibre.
import math, os, sys
centres = {1: (0, 0), 2: (22.4, 0), 3: (44.8, 0), 7: (0, 38.8), 8: (22.4, 38.8), 9: (44.8, 38.8)}
fx, fy = math.sqrt(22.4 ** 2 - 0.375 ** 2) - 7.4, -0.375
def fibre(robot, alpha, beta):
    a, b = math.radians(alpha), math.radians(alpha + beta)
    cx, cy = centres[robot]
    return (cx + 7.4 * math.cos(a) + fx * math.cos(b) - fy * math.sin(b),
            cy + 7.4 * math.sin(a) + fx * math.sin(b) + fy * math.cos(b))
out = sys.argv[1]
with open(out + ".part", "w") as f:
    f.write("robot,x,y\n")
    for spec in sys.argv[2:]:
        parts = spec.split(":")
        robot, alpha, beta = int(parts[0]), float(parts[1]), float(parts[2])
        dx = float(parts[3]) / 1000 if len(parts) > 3 else 0.0
        x, y = fibre(robot, alpha, beta)
        f.write(f"{robot},{x + dx:.6f},{y:.6f}\n")
os.rename(out + ".part", out)  # appears complete
EOF2

start_plane a "$SMALL_PLANE"

# 1. Everyone to (30, 150).
"$AXON" fps plane --layout "$TMP/a.yaml" move --alpha 30 --beta 150 --duration 2 --points 4 \
  >"$TMP/move.out" 2>"$TMP/move.err" || fail "move to (30, 150)"

# 2. Targets (x, y of the boss fibre), and 3. the first measurement: the fibres at (30, 150).
$PY "$TMP/camera.py" "$TMP/t.csv" 1:31:148.5 2:31:148.5 3:31:148.5 7:31:148.5 8:31:148.5 9:30:150:2
$PY "$TMP/camera.py" "$TMP/m1.csv" 1:30:150 2:30:150 3:30:150 7:30:150 8:30:150 9:30:150
"$AXON" fps plane --layout "$TMP/a.yaml" correct --targets "$TMP/t.csv" --measured "$TMP/m1.csv" \
  --measured "$TMP/m2.csv" --wait 60 >"$TMP/c.out" 2>"$TMP/c.err" &
CPID=$!
PIDS+=($CPID)
wait_for_line "$TMP/c.err" "waiting for .*m2.csv" 60 >/dev/null
grep -Eq '^round 1 \(.*m1.csv\): 6 robots, 1 within 5 um, 5 to correct, 0 unreachable' "$TMP/c.out" \
  || fail "round 1 header"
grep -q '^  robot 9: error 2.0 um .*within tolerance, left alone' "$TMP/c.out" || fail "robot 9 should be left alone"
# (31, 148.5) to within the camera file's 1 nm rounding.
grep -Eq '^  robot 1: .*-> alpha (30\.9999|31\.0000)[0-9]* beta 148\.(4999|5000)[0-9]*: arrived' "$TMP/c.out" \
  || fail "robot 1's correction"
# The camera sees each robot where `correct` commanded it (robot 9 where it stayed).
specs=$(sed -nE 's/^  robot ([0-9]+): .*-> alpha ([-0-9.]+) beta ([-0-9.]+): arrived.*/\1:\2:\3/p' "$TMP/c.out")
[ "$(echo "$specs" | wc -l)" = 5 ] || fail "five robots should have arrived"
# shellcheck disable=SC2086
$PY "$TMP/camera.py" "$TMP/m2.csv" $specs 9:30:150
rc=0
wait "$CPID" || rc=$?
[ "$rc" = 0 ] || fail "correct exited $rc"
grep -Eq '^round 2 \(.*m2.csv\): 6 robots, 6 within 5 um, 0 to correct' "$TMP/c.out" || fail "round 2 should be within tolerance"
grep -q '^correction: 2 rounds, every robot within 5 um after 1 correction' "$TMP/c.out" || fail "summary line"

# 4. The robots of gateway 1 read back the corrected angles.
GW1=$($PY -c "import yaml,sys; d=yaml.safe_load(open(sys.argv[1])); print([g['address'] for g in d['gateways'] if g['id']==1][0])" "$TMP/a.yaml")
"$AXON" fps --gateway "$GW1" --channels 1,2 --json position 1,3 >"$TMP/pos.json" 2>"$TMP/pos.err" || fail "position"
$PY - "$TMP/pos.json" <<'EOF2' || fail "robots 1 and 3 not at (31, 148.5)"
import json, sys
p = json.load(open(sys.argv[1]))
for r in ("1", "3"):
    assert abs(p[r]["alpha"] - 31) < 0.01 and abs(p[r]["beta"] - 148.5) < 0.01, p
EOF2

# 5. A measurement naming a robot that is not in the layout.
printf 'robot,x,y\n1,0,0\n44,1,1\n' >"$TMP/bad.csv"
if "$AXON" fps plane --layout "$TMP/a.yaml" correct --targets "$TMP/t.csv" --measured "$TMP/bad.csv" \
  >"$TMP/bad.out" 2>"$TMP/bad.err"; then fail "a bad measurement file should fail"; fi
grep -q 'bad.csv:3: robot 44 is not part of the focal plane' "$TMP/bad.err" || fail "bad.csv error should name file:line"
echo PASS
