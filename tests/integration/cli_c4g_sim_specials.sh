#!/usr/bin/env bash
# Special modes a robot program issues, server and simulator in separate processes: passive freezing
# (502: no packets for a while, 503, mode 0) and restart (506: the initialization packet again,
# without sync packets), then the end of the exchange (504). The monitor app follows all of it.
source "$(dirname "$0")/lib.sh"
skip_without_sim_c4g
start_c4g_serve --app monitor
run_sim_c4g "steps:
  - drive_on
  - freeze_passive: 0.2
  - delay: 0.1
  - restart
  - delay: 0.1
  - exit_open" --reply-deadline-us 20000
[ "$SIM_RC" = 0 ] || fail "simulator exit code $SIM_RC"
wait_serve
[ "$SERVE_RC" = 0 ] || fail "serve exit code $SERVE_RC"
grep -q "axis 1: mode 0 -> 502 (freezing_passive_in)" "$TMP/serve.out" || fail "502 not seen"
grep -q "axis 1: mode 502 -> 503 (freezing_passive_out)" "$TMP/serve.out" || fail "503 not seen after the silence"
grep -q "axis 1: mode 0 -> 506 (server_restart)" "$TMP/serve.out" || fail "506 not seen"
[ "$(grep -c 'initialization packet: 6 open axes' "$TMP/serve.out")" = 2 ] || fail "expected two initialization packets"
grep -q "Packets [0-9]* (init 2," "$TMP/serve.out" || fail "server did not count two initialization packets"
grep -q "controller ended the exchange (504)" "$TMP/serve.out" || fail "504 not seen"
grep -q "Safety: none" "$TMP/serve.out" || fail "a safety fault"
grep -q "(3 sync, 2 init)" "$TMP/sim.out" || fail "the restart must not send sync packets again"
grep -q " 0 misses" "$TMP/sim.out" || fail "misses during the specials"
echo ok
