#!/usr/bin/env bash
# The manual's hand-over example (data/c4g/handover.yaml) with the simulator and `axon c4g serve
# --app handover` as separate processes: the PC plays a relative trajectory in the type A phase
# (mode 4) and a sine correction in the type B phase (mode 7), ending each with exit from open; the
# program goes on after each WAIT FOR PC and ends the exchange (504), which stops the server.
source "$(dirname "$0")/lib.sh"
skip_without_sim_c4g
cat >"$TMP/traj.csv" <<CSV
# units: deg
t,j1,j2,j3,j4,j5,j6
0,0,0,0,0,0,0
0.3,5,-3,2,0,4,0
0.6,0,0,0,0,0,0
CSV
start_c4g_serve --app handover --file "$TMP/traj.csv" --relative --amplitude 0.5,0.5 --frequency 2 --open-time 0.3 --ramp 0.1
run_sim_c4g "$(cat "$(dirname "$0")/../../data/c4g/handover.yaml")"
[ "$SIM_RC" = 0 ] || { cat "$TMP/sim.out" "$TMP/sim.err"; fail "simulator exit code $SIM_RC"; }
wait_serve
[ "$SERVE_RC" = 0 ] || { cat "$TMP/serve.out" "$TMP/serve.err"; fail "serve exit code $SERVE_RC"; }
# Server side: both phases served in order, each ended by exit from open, then the program's end.
order=$(grep -oE 'entered open mode [0-9]+|stream: trajectory started|stream: done|correct: correction started|correct: done|controller ended the exchange' "$TMP/serve.out" | tr '\n' '|')
expected='entered open mode 4|stream: trajectory started|stream: done|entered open mode 7|correct: correction started|correct: done|controller ended the exchange|'
[ "$order" = "$expected" ] || { cat "$TMP/serve.out"; fail "server sequence: $order"; }
grep -q "mode 4 -> 14" "$TMP/serve.out" || fail "no 4 -> 4' on the server"
grep -q "Safety: none" "$TMP/serve.out" || fail "a safety fault"
grep -q "handover: 2 open phases, 1 trajectories in mode 4, 0 in mode 5, 1 corrections" "$TMP/serve.out" || { cat "$TMP/serve.out"; fail "summary"; }
# Simulator side: both open phases ended by the PC, the scenario completed, no communication error.
grep -q "open type A (mode 4) ended" "$TMP/sim.err" || { cat "$TMP/sim.err"; fail "no type A end on the simulator"; }
grep -q "open type B (mode 7) ended" "$TMP/sim.err" || { cat "$TMP/sim.err"; fail "no type B end on the simulator"; }
grep -qi "communication error" "$TMP/sim.err" && fail "communication error on the simulator"
# The same example with nothing to play: the PC holds in mode 4 and adds a zero correction in mode 7.
start_c4g_serve --app handover --open-time 0.2
run_sim_c4g "$(cat "$(dirname "$0")/../../data/c4g/handover.yaml")"
[ "$SIM_RC" = 0 ] || fail "hold: simulator exit code $SIM_RC"
wait_serve
[ "$SERVE_RC" = 0 ] || fail "hold: serve exit code $SERVE_RC"
grep -q "entered open mode 4 (hold 0.200 s)" "$TMP/serve.out" || fail "hold: no mode 4 hold"
grep -q "hold time over" "$TMP/serve.out" || fail "hold: no exit"
grep -q "entered open mode 7 (zero correction 0.200 s)" "$TMP/serve.out" || fail "hold: no zero correction"
grep -q "open type B (mode 7) ended" "$TMP/sim.err" || fail "hold: no type B end"
echo ok
