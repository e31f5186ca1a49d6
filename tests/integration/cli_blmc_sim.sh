#!/usr/bin/env bash
# `axon sim blmc` with two boards over socketcand: each bus (can0, can1) carries its board's 1 Hz
# status; `axon can send` enables the system, the data messages and motor 1 of the board on can1,
# whose data then flows at 1 kHz in the documented order and whose status reports motor 1 ready
# after the alignment, while the board on can0 stays disabled.
source "$(dirname "$0")/lib.sh"
"$AXON" sim blmc --boards 2 --socketcand 127.0.0.1:0 >"$TMP/sim.out" 2>"$TMP/sim.err" &
PIDS+=($!)
PORT=$(wait_for_line "$TMP/sim.out" '^listening socketcand ' | sed 's/.*://')
bus() { echo "socketcand://127.0.0.1:$PORT/$1"; }
dump() { "$AXON" can dump --bus "$(bus "$1")" "${@:2}" 2>>"$TMP/dump.err"; }

for ch in can0 can1; do
  dump $ch --filter 010:7FF --count 1 --timeout 5 >"$TMP/status_$ch.out" || fail "no status frame on $ch"
  grep -q " $ch 010#00$" "$TMP/status_$ch.out" || fail "$ch status: $(cat "$TMP/status_$ch.out")"
done

# ENABLE_SYS=1, SEND_ALL=1 (MDL value, MDH command code, both big-endian).
"$AXON" can send --bus "$(bus can1)" 000#0000000100000001 000#0000000100000014 >/dev/null 2>"$TMP/send.err" \
  || fail "axon can send failed"
dump can1 --filter 020:7FF --filter 030:7FF --filter 040:7FF --filter 050:7FF --count 12 --timeout 5 >"$TMP/data.out" \
  || fail "no data frames on can1"
ids=$(awk '{print substr($3, 1, 3)}' "$TMP/data.out" | xargs)
# Whole cycles in order (the dump may start mid-cycle).
first=$(echo "$ids" | awk '{for (i = 1; i <= NF; i++) if ($i == "020") {print i; exit}}')
cycle=$(echo "$ids" | cut -d' ' -f"$first-$((first + 7))")
[ "$cycle" = "020 030 040 050 020 030 040 050" ] || fail "data order on can1: $ids"
grep -q ' can1 050#0080000000800000$' "$TMP/data.out" || fail "ADC readings: $(cat "$TMP/data.out")"

# ENABLE_MTR1=1: after the alignment, the status says system on, motor 1 enabled and ready (0x07).
"$AXON" can send --bus "$(bus can1)" 000#0000000100000002 >/dev/null 2>>"$TMP/send.err" || fail "axon can send failed"
dump can1 --filter 010:7FF --count 5 --timeout 8 >"$TMP/ready.out" || true
grep -q ' can1 010#07$' "$TMP/ready.out" || fail "motor 1 never became ready: $(cat "$TMP/ready.out")"
grep -q ' can1 010#03$' "$TMP/ready.out" || fail "no status while aligning: $(cat "$TMP/ready.out")"

# The other board was not addressed.
dump can0 --filter 010:7FF --count 1 --timeout 5 >"$TMP/status_can0b.out" || fail "no status frame on can0"
grep -q ' can0 010#00$' "$TMP/status_can0b.out" || fail "can0 changed: $(cat "$TMP/status_can0b.out")"
echo "PASS"
