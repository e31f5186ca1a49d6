#!/usr/bin/env bash
# `axon can replay` plays a candump log onto a bus with its timing; a dump records it again and the
# frames come back in order, with the gaps of the original preserved (checked as a lower bound only).
source "$(dirname "$0")/lib.sh"
start_bridge --listen 127.0.0.1:0
bus="socketcand://127.0.0.1:$SCD_PORT/vcan0"
cat >"$TMP/in.log" <<'LOG'
(1700000000.000000) can0 100#01
(1700000000.200000) can0 101#0202
(1700000000.400000) can0 00000102#030303
(1700000000.400100) can0 103#R
LOG
"$AXON" can dump --bus "$bus" --count 4 --timeout 20 --log "$TMP/out.log" >"$TMP/dump.out" 2>"$TMP/dump.err" &
d=$!; PIDS+=($d)
wait_for_line "$TMP/dump.err" 'receiving on' >/dev/null
"$AXON" can replay --bus "$bus" "$TMP/in.log" >"$TMP/replay.out" 2>"$TMP/replay.err" || fail "replay failed"
wait "$d" || fail "dump exited with $?"
got=$(awk '{print $3}' "$TMP/out.log" | xargs)
[ "$got" = "100#01 101#0202 00000102#030303 103#R" ] || fail "replayed frames: '$got'"
# The first and third frames were 0.4 s apart in the original; the copy must not be faster.
gap=$(awk 'NR==1{gsub(/[()]/,"",$1); a=$1} NR==3{gsub(/[()]/,"",$1); b=$1} END{printf "%.3f", b-a}' "$TMP/out.log")
awk -v g="$gap" 'BEGIN{exit !(g >= 0.38)}' || fail "replay did not keep timing: gap $gap s"
grep -q "4 frames" "$TMP/replay.err" "$TMP/replay.out" || fail "replay did not report what it sent"
echo "PASS"
