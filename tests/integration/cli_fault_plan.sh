#!/usr/bin/env bash
# A bridge with a YAML fault plan: the second frame with id 0x123 is dropped on the virtual bus and
# every frame with id 0x200 is duplicated; a dump across socketcand sees exactly that.
source "$(dirname "$0")/lib.sh"
cat >"$TMP/faults.yaml" <<'YAML'
seed: 3
rules:
  - action: drop
    id: 0x123
    skip: 1
    count: 1
  - action: duplicate
    id: 0x200
YAML
start_bridge --listen 127.0.0.1:0 --fault-plan "$TMP/faults.yaml"
bus="socketcand://127.0.0.1:$SCD_PORT/vcan0"
"$AXON" can dump --bus "$bus" --count 5 --timeout 20 >"$TMP/dump.out" 2>"$TMP/dump.err" &
d=$!; PIDS+=($d)
wait_for_line "$TMP/dump.err" 'receiving on' >/dev/null
"$AXON" can send --bus "$bus" 123#01 123#02 123#03 200#AA 124#04 2>"$TMP/send.err" || fail "send failed"
wait "$d" || fail "dump exited with $?"
got=$(awk '{print $3}' "$TMP/dump.out" | xargs)
[ "$got" = "123#01 123#03 200#AA 200#AA 124#04" ] || fail "got '$got'"
grep -q "fault plan" "$TMP/bridge.err" || fail "bridge did not report its fault plan"
# A broken plan is refused with the file, line and key.
printf 'rules:\n  - action: explode\n' >"$TMP/bad.yaml"
if "$AXON" can bridge --listen 127.0.0.1:0 --fault-plan "$TMP/bad.yaml" --duration 1 >/dev/null 2>"$TMP/bad.err"; then
  fail "bridge accepted a bad fault plan"
fi
grep -q "bad.yaml:2:" "$TMP/bad.err" || fail "error does not locate the bad key: $(cat "$TMP/bad.err")"
echo "PASS"
