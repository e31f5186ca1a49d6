#!/usr/bin/env bash
# `axon can bridge` serves a virtual bus over socketcand; `axon can dump` (one process) receives
# what `axon can send` (another process) sends, and writes a candump log of it.
source "$(dirname "$0")/lib.sh"
start_bridge --listen 127.0.0.1:0
bus="socketcand://127.0.0.1:$SCD_PORT/vcan0"

"$AXON" can dump --bus "$bus" --count 4 --timeout 20 --log "$TMP/dump.log" >"$TMP/dump.out" 2>"$TMP/dump.err" &
dump=$!; PIDS+=($dump)
wait_for_line "$TMP/dump.err" 'receiving on' >/dev/null

"$AXON" can send --bus "$bus" 123#DEADBEEF 1ABCDEF0#0102030405060708 7FF# 00000001#R >"$TMP/send.out" 2>"$TMP/send.err" \
  || fail "axon can send failed"
wait "$dump" || fail "axon can dump exited with $?"

expected="123#DEADBEEF 1ABCDEF0#0102030405060708 7FF# 00000001#R"
got=$(awk '{print $3}' "$TMP/dump.out" | xargs)
[ "$got" = "$expected" ] || fail "dump printed '$got', expected '$expected'"
logged=$(awk '{print $3}' "$TMP/dump.log" | xargs)
[ "$logged" = "$expected" ] || fail "log holds '$logged', expected '$expected'"
grep -Eq '^\([0-9]+\.[0-9]{6}\) vcan0 123#DEADBEEF$' "$TMP/dump.log" || fail "log line not in candump format"
echo "PASS"
