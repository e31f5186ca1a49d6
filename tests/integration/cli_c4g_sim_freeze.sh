#!/usr/bin/env bash
# Active freezing (500) from the command line against the simulator: --freeze-at / --freeze-for,
# then SIGUSR1 / SIGUSR2. Both sides report the freeze and its end; no safety fault, clean exit.
source "$(dirname "$0")/lib.sh"
skip_without_sim_c4g
# 1. Timed: frozen from 1 s after start (the robot is in mode 0 by then) for 0.4 s.
start_c4g_serve --app monitor --freeze-at 1.0 --freeze-for 0.4
run_sim_c4g "steps:
  - drive_on
  - delay: 2.5
  - exit_open"
[ "$SIM_RC" = 0 ] || { cat "$TMP/sim.err"; fail "timed: simulator exit code $SIM_RC"; }
wait_serve
[ "$SERVE_RC" = 0 ] || { cat "$TMP/serve.out"; fail "timed: serve exit code $SERVE_RC"; }
# (entering / leaving last a packet or two: printed only when the 20 ms poll sees them)
order=$(grep -E '^freeze: ' "$TMP/serve.out" | grep -vE 'entering|leaving|pending' | tr '\n' '|')
expected='freeze: requested (--freeze-at 1.000 s)|freeze: frozen|freeze: released (--freeze-for 0.400 s)|freeze: off|'
[ "$order" = "$expected" ] || { cat "$TMP/serve.out"; fail "timed: freeze sequence: $order"; }
grep -q "active freezing (500) from the PC" "$TMP/sim.err" || { cat "$TMP/sim.err"; fail "timed: the simulator did not freeze"; }
grep -q "active freezing ended by the PC's exit-from-open" "$TMP/sim.err" || fail "timed: the simulator did not leave the freeze"
grep -q "freezes 1, now off" "$TMP/serve.out" || { cat "$TMP/serve.out"; fail "timed: summary"; }
grep -q "Safety: none" "$TMP/serve.out" || fail "timed: a safety fault"
# 2. Signals: SIGUSR1 freezes, SIGUSR2 releases, while the program idles.
start_c4g_serve --app monitor
(run_sim_c4g "steps:
  - drive_on
  - delay: 4
  - exit_open"; echo "$SIM_RC" >"$TMP/sim.rc") &
SIM_JOB=$!
wait_for_line "$TMP/serve.out" 'arm 1: drives on' >/dev/null
kill -USR1 "$SERVE_PID"
wait_for_line "$TMP/serve.out" '^freeze: frozen' >/dev/null
kill -USR2 "$SERVE_PID"
wait_for_line "$TMP/serve.out" '^freeze: off' >/dev/null
wait "$SIM_JOB"
[ "$(cat "$TMP/sim.rc")" = 0 ] || { cat "$TMP/sim.err"; fail "signals: simulator exit code $(cat "$TMP/sim.rc")"; }
wait_serve
[ "$SERVE_RC" = 0 ] || { cat "$TMP/serve.out"; fail "signals: serve exit code $SERVE_RC"; }
grep -q '^freeze: requested (SIGUSR1)' "$TMP/serve.out" || fail "signals: no SIGUSR1 line"
grep -q '^freeze: released (SIGUSR2)' "$TMP/serve.out" || fail "signals: no SIGUSR2 line"
grep -q "active freezing ended by the PC's exit-from-open" "$TMP/sim.err" || fail "signals: the simulator did not leave the freeze"
grep -q "Safety: none" "$TMP/serve.out" || fail "signals: a safety fault"
echo ok
