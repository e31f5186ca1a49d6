#!/usr/bin/env bash
# SIGTERM at any moment of `axon c4g serve`'s end: a service manager or a shell script's clean-up
# (the documented examples' runner among them) signals a server that is already stopping. Each run:
# the controller's program ends, the server ends its session by itself, and SIGTERM comes every
# millisecond from then until the process is gone. The exit code must stay the run's (0) and the
# report must be printed: a signal during the clean-up is not a crash. Before the fix, a signal that
# came after the command had restored the default action killed the process (exit 143).
source "$(dirname "$0")/lib.sh"
skip_without_sim_c4g
for run in 1 2 3 4 5; do
  start_c4g_serve --app echo
  run_sim_c4g "steps:
  - drive_on
  - exit_open"
  [ "$SIM_RC" = 0 ] || fail "run $run: simulator exit code $SIM_RC"
  while kill -TERM "$SERVE_PID" 2>/dev/null; do sleep 0.001; done
  SERVE_RC=0
  wait "$SERVE_PID" || SERVE_RC=$?
  [ "$SERVE_RC" = 0 ] || fail "run $run: serve exit code $SERVE_RC under a SIGTERM storm at its end"
  grep -q "^Safety: " "$TMP/serve.out" || fail "run $run: no report printed"
done
echo ok
