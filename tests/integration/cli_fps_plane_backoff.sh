#!/usr/bin/env bash
# `axon fps plane backoff` between processes, after a real collision in the simulator:
#  1. every robot to (0, 180) with `fps plane move`;
#  2. robot 1 stretched towards robot 2 (`fps goto 1 0 20`): the simulator stops it where it
#     touches robot 2's collision buffer and reports the collision (the goto fails);
#  3. `backoff` without --unlock: the robot's collision flag refuses the move, exit 1;
#  4. `backoff --unlock`: the flags cleared, robot 1 moved 2 degrees or more out of the contact,
#     nothing left in contact, exit 0; --json says the same;
#  5. `backoff 99`: a robot the layout does not have is refused with a clear error.
source "$(dirname "$0")/lib.sh"

start_plane a "$SMALL_PLANE"
"$AXON" fps plane --layout "$TMP/a.yaml" move --alpha 0 --beta 180 --duration 2 --points 4 \
  >"$TMP/move.out" 2>"$TMP/move.err" || fail "move to (0, 180)"

gw1=$(sed -nE 's/.*\{id: 1, address: "?([0-9.]+:[0-9]+)"?.*/\1/p' "$TMP/a.yaml" | head -n 1)
[ -n "$gw1" ] || fail "no address for gateway 1 in the written layout"
if "$AXON" fps --bus "cannet://$gw1/1" goto 1 0 20 >"$TMP/goto.out" 2>"$TMP/goto.err"; then
  fail "robot 1 went through robot 2"
fi
grep -qi "collision" "$TMP/goto.out" "$TMP/goto.err" || fail "the goto did not report the collision"

"$AXON" fps plane --layout "$TMP/a.yaml" backoff >"$TMP/b0.out" 2>"$TMP/b0.err" && fail "backoff moved a robot whose collision flag is set"
grep -q '^contact before: robot 1 / robot 2 (-' "$TMP/b0.out" || fail "the contact was not listed"
grep -q '^robot 1: not moved: the move failed' "$TMP/b0.out" || fail "the refused move was not reported"

"$AXON" fps plane --layout "$TMP/a.yaml" backoff --unlock >"$TMP/b1.out" 2>"$TMP/b1.err" || fail "backoff --unlock"
grep -Eq '^robot 1: (alpha|beta) [-+][2-8]\.0 deg, .* -> [0-9.]+ mm$' "$TMP/b1.out" || fail "robot 1 was not moved out"
grep -q '^contact left' "$TMP/b1.out" && fail "a contact is left"

"$AXON" fps plane --layout "$TMP/a.yaml" backoff --json >"$TMP/b2.out" 2>"$TMP/b2.err" || fail "backoff --json"
/usr/bin/python3 - "$TMP/b2.out" <<'PY' || fail "the JSON report"
import json, sys
r = json.load(open(sys.argv[1]))
assert r["ok"] is True and r["contacts_before"] == [] and r["moves"] == [] and r["contacts_after"] == [], r
PY

"$AXON" fps plane --layout "$TMP/a.yaml" backoff 99 >"$TMP/b3.out" 2>"$TMP/b3.err" && fail "robot 99 accepted"
grep -q "robot 99 is not in the layout" "$TMP/b3.err" || fail "no clear error for robot 99"
echo PASS
