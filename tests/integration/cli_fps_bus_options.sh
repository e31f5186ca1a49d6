#!/usr/bin/env bash
# Bus options and input files of `axon fps`, against `axon sim fps` (robots 1-3 on channel 1, 4-6 on
# channel 2 of one CAN@net emulator) in another process:
#   1. two --bus cannet:// channels of one gateway share one connection: every robot is found;
#   2. the same bus twice, a negative --timeout, a robot twice in a trajectory file, a channel twice
#      in a bus configuration file: refused (exit 2), duplicates with both lines;
#   3. --timeout 0 leaves every robot silent: a failure (exit 1), not a status.
source "$(dirname "$0")/lib.sh"
start_sim_fps --robots 1-6 --buses 2 --gateway 127.0.0.1:0 --time-scale 20
GW="127.0.0.1:$SIM_CANNET_PORT"

# 1. Two channels of one gateway.
"$AXON" fps --bus "cannet://$GW/1" --bus "cannet://$GW/2" discover >"$TMP/d.out" 2>"$TMP/d.err" \
  || fail "discover over two --bus channels exited with $?"
grep -Eq '/1: 3 robots: 1 2 3$' "$TMP/d.out" || fail "channel 1's robots not found"
grep -Eq '/2: 3 robots: 4 5 6$' "$TMP/d.out" || fail "channel 2's robots not found"
grep -qi 'failed' "$TMP/d.err" && fail "a discovery failed: $(cat "$TMP/d.err")"

# expect_usage WHAT REGEX ARGS...: exit 2 and REGEX on stderr.
expect_usage() {
  local what=$1 re=$2; shift 2
  set +e
  "$AXON" "$@" >"$TMP/u.out" 2>"$TMP/u.err"
  local rc=$?
  set -e
  [ $rc = 2 ] || fail "$what: exit code $rc, expected 2"
  grep -Eq "$re" "$TMP/u.err" || fail "$what: no /$re/ in: $(cat "$TMP/u.err")"
}

# 2. Bad values and duplicates.
expect_usage "the same bus twice" "listed twice" fps --bus "cannet://$GW/1" --bus "cannet://$GW/1" discover
expect_usage "a negative timeout" "must be >= 0, got -1" fps --gateway "$GW" --timeout -1 status
cat >"$TMP/traj.yaml" <<'YAML'
1: {alpha: [[10, 1.0]]}
2: {alpha: [[15, 1.5]]}
1: {alpha: [[20, 2.0]]}
YAML
expect_usage "a robot twice in a trajectory file" "traj.yaml:3: robot 1 listed twice \(first at line 1\)" \
  fps --gateway "$GW" move --trajectory "$TMP/traj.yaml"
cat >"$TMP/buses.yaml" <<YAML
gateway: $GW
channels:
  - 1
  - 2
  - 1
YAML
expect_usage "a channel twice in a bus file" "buses.yaml:5:.*channel 1 listed twice \(first at line 3\)" \
  fps --config "$TMP/buses.yaml" status

# 3. --timeout 0: the robots are found by the discovery window, then every read times out.
set +e
"$AXON" fps --gateway "$GW" --channels 1,2 --timeout 0 status >"$TMP/t0.out" 2>"$TMP/t0.err"
rc=$?
set -e
[ $rc = 1 ] || fail "--timeout 0 with every robot silent: exit code $rc, expected 1"
echo PASS
