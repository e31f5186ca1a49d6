#!/usr/bin/env bash
# The server killed mid-run: the simulator reports the manual's communication error after ten
# missing answers.
source "$(dirname "$0")/lib.sh"
skip_without_sim_c4g
start_c4g_serve --app monitor
( sleep 1; kill -9 "$SERVE_PID" ) &
run_sim_c4g "steps:
  - drive_on
  - run" --duration 5
[ "$SIM_RC" != 0 ] || fail "the simulator did not report an error"
grep -qi "communication error" "$TMP/sim.out" "$TMP/sim.err" || fail "no communication error reported"
echo ok
