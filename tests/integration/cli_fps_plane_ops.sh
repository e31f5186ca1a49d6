#!/usr/bin/env bash
# Whole-plane operations between processes: `axon sim fps --layout` (CAN@net emulators + PLC
# emulator) driven by `axon fps plane upgrade` (firmware of every sextant through the PLC) and
# `axon fps plane cold` (the cold-temperature policy from the PLC's temperatures).
source "$(dirname "$0")/lib.sh"

start_plane a "$SMALL_PLANE"

# 1. Firmware of every robot, sextant by sextant; a progress line per sextant on stderr.
{ printf 'AXON-FPS-FW:04.02.00'; head -c 4000 /dev/zero | tr '\0' 'x'; } >"$TMP/fw.bin"
"$AXON" fps plane --layout "$TMP/a.yaml" --plc "$PLC" upgrade --image "$TMP/fw.bin" --version 4.2.0 --power-off 0.1 \
  >"$TMP/up.out" 2>"$TMP/up.err" || fail "upgrade failed"
grep -Eq '^sextant 1: 3/3 robots, [0-9.]+ MB in' "$TMP/up.err" || fail "no progress line for sextant 1"
grep -Eq '^sextant 2: 3/3 robots, [0-9.]+ MB in' "$TMP/up.err" || fail "no progress line for sextant 2"
grep -q ': 6 ok, 0 failed, 0 not attempted' "$TMP/up.out" || fail "not every robot upgraded"
grep -q 'positioner 9 (sextant 2): ok, 1 attempt, runs 04.02.00' "$TMP/up.out" || fail "robot 9 not on 04.02.00"
"$AXON" fps plane --layout "$TMP/a.yaml" status >"$TMP/st.out" 2>"$TMP/st.err" || fail "status after the upgrade"
grep -Eq '^  ready: 6$' "$TMP/st.out" || fail "robots should be back in their application"
# 2. The cold policy once: the emulated PLC reads 15 degC, so normal speed and no heating, sent to all.
"$AXON" fps plane --layout "$TMP/a.yaml" --plc "$PLC" cold >"$TMP/cold.out" 2>"$TMP/cold.err" || fail "cold policy"
grep -q '^cold policy: speed 5000 rpm, holding current alpha 0 % beta 30 %' "$TMP/cold.out" || fail "wrong cold decision"
grep -q 'applied to 6 robots, 0 failed' "$TMP/cold.out" || fail "cold settings not applied to every robot"
"$AXON" fps plane --layout "$TMP/a.yaml" --plc "$PLC" cold --watch --period 0.2 --for 0.7 >"$TMP/coldw.out" 2>"$TMP/coldw.err" \
  || fail "cold --watch"
[ "$(grep -c 'applied to 6 robots' "$TMP/coldw.out")" = 1 ] || fail "cold --watch should send once (no change)"
echo PASS
