#!/usr/bin/env bash
# Mode 0' against the simulator: the echo app returns the targets while the controller moves.
source "$(dirname "$0")/lib.sh"
skip_without_sim_c4g
start_c4g_serve --app echo
run_sim_c4g "steps:
  - drive_on
  - go_open: {type: B, mode: \"0'\", arms: [1]}
  - move: {arm: 1, deg: [3, 0, 0, 0, 0, 0], duration: 0.3}
  - go_open: {type: A, mode: 0, arms: [1]}
  - exit_open"
[ "$SIM_RC" = 0 ] || fail "simulator exit code $SIM_RC"
wait_serve
[ "$SERVE_RC" = 0 ] || fail "serve exit code $SERVE_RC"
# The program opens 0' right after the drive-on procedure: the manual (driving on) has SM go from 501
# straight to the mode the program set, so the change seen is 501 -> 10.
grep -q "axis 1: mode 501 -> 10 (mode0_prime)" "$TMP/serve.out" || fail "mode 0' not entered"
grep -q "axis 1: mode 10 -> 0 (mode0)" "$TMP/serve.out" || fail "mode 0' not left for mode 0"
grep -Eq "echo: [1-9][0-9]+ cycles echoed" "$TMP/serve.out" || fail "nothing echoed"
echo ok
