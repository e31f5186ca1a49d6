#!/usr/bin/env bash
# Modes 8 and 9 between separate processes: `axon c4g serve --app contribute` adds a velocity (8)
# or current (9) sine to the controller's loops while the simulated robot program holds the open
# mode, then fades it out and leaves the mode; the simulator must see no fault.
source "$(dirname "$0")/lib.sh"
skip_without_sim_c4g
for mode in 9 8; do
  if [ "$mode" = 9 ]; then amp=3; else amp=0.5; fi
  start_c4g_serve --app contribute --mode "$mode" --amplitude "$amp" --frequency 2 --open-time 0.6 --ramp 0.1
  run_sim_c4g "steps:
  - drive_on
  - go_open: {type: B, mode: $mode, arms: [1]}
  - wait_for_pc: {timeout: 10}
  - exit_open"
  [ "$SIM_RC" = 0 ] || fail "mode $mode: simulator exit code $SIM_RC: $(tail -5 "$TMP/sim.out")"
  wait_serve
  [ "$SERVE_RC" = 0 ] || fail "mode $mode: serve exit code $SERVE_RC"
  grep -q "contribute: .* contribution started (mode $mode, arm 1)" "$TMP/serve.out" || fail "mode $mode: not started"
  grep -q "contribute: done" "$TMP/serve.out" || fail "mode $mode: not done"
  grep -q "Safety: none" "$TMP/serve.out" || fail "mode $mode: a safety fault"
  # The peak sent on axis 1 is the amplitude (within the sampling of a 2 Hz sine at the cycle rate).
  peak=$(grep -Eo "peak per axis [0-9.]+" "$TMP/serve.out" | awk '{print $4}')
  awk -v p="$peak" -v a="$amp" 'BEGIN { exit !(p > 0.95 * a && p <= a * 1.0001) }' || fail "mode $mode: peak $peak, amplitude $amp"
  grep -Eiq "communication error|SCS_|fault" "$TMP/sim.out" && fail "mode $mode: simulator reports: $(grep -Ei 'communication error|SCS_|fault' "$TMP/sim.out" | head -3)"
done
echo ok
