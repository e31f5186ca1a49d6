#!/usr/bin/env bash
# The focal plane at scale, over real TCP between processes: `axon sim fps --layout` (one CAN@net
# emulator per gateway plus the PLC emulator) driven by `axon fps plane` and `axon fps plc`.
#   1. discovery against the layout finds a missing robot and an extra one;
#   2. a move by the sync line is refused while a robot it reaches is silent, and otherwise reaches every bus;
#   3. a sextant powered off and on through the PLC mid-session: silent, then in the bootloader;
#   4. a collision on one bus stops the robots of every bus.
source "$(dirname "$0")/lib.sh"

cat >"$TMP/plane.yaml" <<'EOF'
name: two-sextants
pitch_mm: 22.4
gateways:
  - {id: 1, address: "127.0.0.1:1", sextant: 1, channels: 4}
  - {id: 2, address: "127.0.0.1:1", sextant: 2, channels: 4}
robots:
  - {id: 1, x: 0, y: 0, sextant: 1, gateway: 1, bus: 1, fibres: [boss]}
  - {id: 2, x: 22.4, y: 0, sextant: 1, gateway: 1, bus: 1, fibres: [boss]}
  - {id: 3, x: 44.8, y: 0, sextant: 1, gateway: 1, bus: 1, fibres: [boss]}
  - {id: 4, x: 67.2, y: 0, sextant: 1, gateway: 1, bus: 2, fibres: [boss]}
  - {id: 5, x: 89.6, y: 0, sextant: 1, gateway: 1, bus: 2, fibres: [boss]}
  - {id: 6, x: 112, y: 0, sextant: 1, gateway: 1, bus: 2, fibres: [boss]}
  - {id: 7, x: 0, y: 38.8, sextant: 2, gateway: 2, bus: 1, fibres: [boss]}
  - {id: 8, x: 22.4, y: 38.8, sextant: 2, gateway: 2, bus: 1, fibres: [boss]}
  - {id: 9, x: 44.8, y: 38.8, sextant: 2, gateway: 2, bus: 1, fibres: [boss]}
  - {id: 10, x: 67.2, y: 38.8, sextant: 2, gateway: 2, bus: 2, fibres: [boss]}
  - {id: 11, x: 89.6, y: 38.8, sextant: 2, gateway: 2, bus: 2, fibres: [boss]}
  - {id: 12, x: 112, y: 38.8, sextant: 2, gateway: 2, bus: 2, fibres: [boss]}
EOF

# plane NAME ARGS...: lib.sh's simulated plane on this test's layout, one gateway line each.
plane() {
  local name=$1; shift
  start_plane "$name" "$TMP/plane.yaml" "$@"
  [ "$(grep -c '^listening gateway ' "$TMP/$name.out")" = 2 ] || fail "expected one ready line per gateway"
}

# 1. Discovery with a robot missing and one too many.
cat >"$TMP/scenario.yaml" <<'EOF'
absent: [5]
extra: [{id: 900, gateway: 2, bus: 1}]
EOF
plane a --scenario "$TMP/scenario.yaml"
set +e
"$AXON" fps plane --layout "$TMP/a.yaml" check --window 0.3 >"$TMP/check.out" 2>"$TMP/check.err"
rc=$?
set -e
[ $rc = 1 ] || fail "layout check should fail (rc $rc)"
grep -q '^missing *robot 5 ' "$TMP/check.out" || fail "robot 5 not reported missing"
grep -q '^unexpected *robot 900 ' "$TMP/check.out" || fail "robot 900 not reported unexpected"
grep -q '11 matched' "$TMP/check.out" || fail "11 robots should match (12 in the layout, robot 5 absent)"

# 2. The sync line reaches every robot: with robot 5 silent (absent) it could start a trajectory
#    robot 5 may hold, so a move by the sync line is refused, naming it, and the line stays low.
set +e
"$AXON" fps plane --layout "$TMP/a.yaml" --plc "$PLC" move --alpha 20 --beta 170 --duration 4 --sync \
  >"$TMP/refused.out" 2>"$TMP/refused.err"
rc=$?
set -e
[ $rc != 0 ] || fail "a sync move with a silent robot must be refused"
grep -q 'start by the sync line refused.*: 5 (no acknowledgement)' "$TMP/refused.err" || fail "refusal does not name robot 5"
grep -q 'sync line rising edge: ' "$TMP/a.err" && fail "the sync line was pulsed despite the refusal"
# With every robot answering, a move started by the sync line (held 0.5 s by default) reaches
# every bus; the final approach (interface document 7.3) then brings every robot back to its target.
PLC_A=$PLC
plane c
"$AXON" fps plane --layout "$TMP/c.yaml" --plc "$PLC" move --alpha 20 --beta 170 --duration 4 --sync --approach \
  >"$TMP/move.out" 2>"$TMP/move.err" || fail "sync move failed"
for bus in gw1/1 gw1/2 gw2/1 gw2/2; do
  grep -Eq "^bus $bus: ([0-9]+) of \1 robots started" "$TMP/move.out" || fail "not every robot on $bus started"
done
grep -q 'start by the sync line' "$TMP/move.out" || fail "not started by the sync line"
grep -q '^completed: 12 robots' "$TMP/move.out" || fail "move did not complete"
grep -q 'sync line rising edge: ' "$TMP/c.err" || fail "the simulator saw no sync edge"
grep -Eq 'sync line low after (0\.[5-9]|[1-9])[0-9.]* s high' "$TMP/c.err" || fail "the sync line was held less than 0.5 s"
grep -q '^final approach .*: 12 of 12 robots at their targets' "$TMP/move.out" || fail "final approach did not bring every robot back"
PLC=$PLC_A

# 3. Sextant 2 powered off, then on through the PLC, while the host keeps working.
"$AXON" fps plc --host "$PLC" power 2 off >/dev/null || fail "power off"
"$AXON" fps plane --layout "$TMP/a.yaml" status >"$TMP/off.out" 2>"$TMP/off.err" || true
# Silent: the 6 robots of sextant 2 and the absent robot 5; ready: the other 5 of sextant 1 and
# the extra robot 900 (not in a sextant: no relay switches it).
grep -Eq '^  no answer: 7$' "$TMP/off.out" || fail "sextant 2 should be silent"
grep -Eq '^  ready: 6$' "$TMP/off.out" || fail "sextant 1 should stay ready"
"$AXON" fps plc --host "$PLC" power 2 on >/dev/null || fail "power on"
"$AXON" fps plane --layout "$TMP/a.yaml" status >"$TMP/on.out" 2>"$TMP/on.err" || true
grep -Eq '^  bootloader: 6$' "$TMP/on.out" || fail "sextant 2 should be in the bootloader (sync line low)"

# 4. A collision of robot 8 (gateway 2, bus 1) stops every robot on every bus.
cat >"$TMP/collide.yaml" <<'EOF'
collide_on_move: [8]
EOF
plane b --scenario "$TMP/collide.yaml"
set +e
"$AXON" fps plane --layout "$TMP/b.yaml" --plc "$PLC" move --alpha 90 --beta 120 --duration 40 --sync \
  >"$TMP/coll.out" 2>"$TMP/coll.err"
rc=$?
set -e
[ $rc = 4 ] || fail "a collided move must end in a safety stop (rc $rc, expected 4)"
grep -q '^locked: ' "$TMP/coll.out" || fail "the array did not lock"
grep -q 'positioner 8: collided' "$TMP/coll.out" || fail "robot 8 not reported collided"
for id in 1 4 7 10 12; do
  grep -q "positioner $id: stopped" "$TMP/coll.out" || fail "robot $id was not stopped"
done
echo PASS
