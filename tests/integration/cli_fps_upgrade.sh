#!/usr/bin/env bash
# Robots powered with the sync line low sit in their bootloader; `axon fps upgrade` sends them an
# image over CAN@net, shows progress on stderr and reports each robot.
source "$(dirname "$0")/lib.sh"
printf 'defaults: {sync_line_low_at_power_on: true}\ngrid: {count: 2, buses: [can0]}\n' >"$TMP/boot.yaml"
{ printf 'AXON-FPS-FW:04.02.00'; head -c 3000 /dev/zero; } >"$TMP/fw.bin"
start_sim_fps --config "$TMP/boot.yaml" --gateway 127.0.0.1:0
fps() { "$AXON" fps --gateway "127.0.0.1:$SIM_CANNET_PORT" "$@"; }

fps discover >"$TMP/discover.out" 2>"$TMP/discover.err" || fail "discover exited with $?"
grep -q 'firmware 03.80' "$TMP/discover.out" || fail "robots are not in their bootloader"
fps upgrade --firmware "$TMP/fw.bin" 1-2 >"$TMP/upgrade.out" 2>"$TMP/upgrade.err" || fail "upgrade exited with $?"
grep -q '2 ok, 0 failed' "$TMP/upgrade.out" || fail "upgrade report: $(cat "$TMP/upgrade.out")"
grep -q 'upgrade: robot 1: 378/378 frames' "$TMP/upgrade.err" || fail "no progress on stderr"
echo "PASS"
