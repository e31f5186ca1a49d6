#!/usr/bin/env bash
# Mode 7 against the simulator: a sine correction on top of the controller's move, faded out,
# exit from open, back to mode 0.
source "$(dirname "$0")/lib.sh"
skip_without_sim_c4g
start_c4g_serve --app correct --amplitude 0.5,0.5 --frequency 2 --open-time 0.5 --ramp 0.2
run_sim_c4g "steps:
  - drive_on
  - go_open: {type: B, mode: 7, arms: [1]}
  - move: {arm: 1, deg: [5, 0, 0, 0, 0, 0], duration: 0.5}
  - wait_for_pc: {timeout: 10}
  - exit_open"
[ "$SIM_RC" = 0 ] || fail "simulator exit code $SIM_RC"
wait_serve
[ "$SERVE_RC" = 0 ] || fail "serve exit code $SERVE_RC"
grep -q "correct: correction started" "$TMP/serve.out" || fail "not started"
grep -q "correct: done" "$TMP/serve.out" || fail "not done"
grep -q "Safety: none" "$TMP/serve.out" || fail "a safety fault"
echo ok
