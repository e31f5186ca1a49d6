#!/usr/bin/env bash
# One bridge serves the same virtual bus over socketcand and as a CAN@net gateway emulator.
# Frames sent through CAN@net arrive at a socketcand dump and the other way round (a CAN@net
# gateway serves one client at a time, so each direction uses one client of each kind).
source "$(dirname "$0")/lib.sh"
start_bridge --listen 127.0.0.1:0 --listen cannet://127.0.0.1:0
scd="socketcand://127.0.0.1:$SCD_PORT/vcan0"
cannet="cannet://127.0.0.1:$CANNET_PORT/1"

# CAN@net -> socketcand
"$AXON" can dump --bus "$scd" --count 2 --timeout 20 >"$TMP/dump1.out" 2>"$TMP/dump1.err" &
d=$!; PIDS+=($d)
wait_for_line "$TMP/dump1.err" 'receiving on' >/dev/null
"$AXON" can send --bus "$cannet" 12345678#CAFE 010#00112233 2>"$TMP/send1.err" || fail "send over CAN@net failed"
wait "$d" || fail "socketcand dump exited with $?"
got=$(awk '{print $3}' "$TMP/dump1.out" | xargs)
[ "$got" = "12345678#CAFE 010#00112233" ] || fail "CAN@net -> socketcand: got '$got'"

# socketcand -> CAN@net
"$AXON" can dump --bus "$cannet" --count 2 --timeout 20 >"$TMP/dump2.out" 2>"$TMP/dump2.err" &
d=$!; PIDS+=($d)
wait_for_line "$TMP/dump2.err" 'receiving on' >/dev/null
"$AXON" can send --bus "$scd" 7FF#01 1FFFFFFF#FFFFFFFFFFFFFFFF 2>"$TMP/send2.err" || fail "send over socketcand failed"
wait "$d" || fail "CAN@net dump exited with $?"
got=$(awk '{print $3}' "$TMP/dump2.out" | xargs)
[ "$got" = "7FF#01 1FFFFFFF#FFFFFFFFFFFFFFFF" ] || fail "socketcand -> CAN@net: got '$got'"
echo "PASS"
