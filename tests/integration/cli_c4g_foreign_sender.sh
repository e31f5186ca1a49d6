#!/usr/bin/env bash
# A stranger on the server's port: `axon c4g serve` in one process, the simulated controller in a
# second, and a third process firing datagrams of the controller's size (228 bytes, six axes) from
# its own port while the session runs: undecodable ones (NaN), well-formed cyclic packets and an
# initialization packet. None may be answered or change the session: the controller finishes its
# program without a fault, the server latches nothing, and the foreign datagrams are counted in the
# status lines and the final report (text, then JSON).
source "$(dirname "$0")/lib.sh"
skip_without_sim_c4g

# stranger PORT SECONDS: sends every 5 ms for SECONDS; prints how many it sent and answers it got.
cat >"$TMP/stranger.py" <<'PY'
import socket, struct, sys, time
port, seconds = int(sys.argv[1]), float(sys.argv[2])
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
s.bind(("127.0.0.1", 0))
s.setblocking(False)
nan = struct.pack("<f", float("nan"))
def cyclic(num, mode, d1=b"\0\0\0\0"):
    return struct.pack("<iii", num, 5, 0) + b"".join(struct.pack("<i", mode) + d1 + b"\0" * 28 for _ in range(6))
init = bytearray(1200)
struct.pack_into("<iiii", init, 0, 77, 3, 9, 6)
struct.pack_into("<i", init, 224, 2)
packets = [cyclic(1, 10, nan), cyclic(2, 0), bytes(init), cyclic(3, 505, nan)]
assert all(len(p) in (228, 1200) for p in packets)
sent = answers = 0
end = time.time() + seconds
while time.time() < end:
    s.sendto(packets[sent % len(packets)], ("127.0.0.1", port))
    sent += 1
    time.sleep(0.005)
    try:
        while True:
            s.recv(2048)
            answers += 1
    except BlockingIOError:
        pass
print(f"stranger sent {sent} answers {answers}")
PY

SCENARIO="steps:
  - drive_on
  - go_open: {type: B, mode: \"0'\", arms: [1]}
  - move: {arm: 1, deg: [3, 0, 0, 0, 0, 0], duration: 1.5}
  - go_open: {type: A, mode: 0, arms: [1]}
  - exit_open"

# stranger_after_init: starts the stranger once the controller's initialization packet was served.
stranger_after_init() {
  ( wait_for_line "$TMP/$1" 'initialization packet' >/dev/null
    python3 "$TMP/stranger.py" "$C4G_PORT" 1.2 >"$TMP/stranger.out" ) &
  STRANGER=$!
  PIDS+=($STRANGER)
}

check_run() {
  [ "$SIM_RC" = 0 ] || fail "simulator exit code $SIM_RC (the stranger disturbed the session)"
  wait_serve
  [ "$SERVE_RC" = 0 ] || fail "serve exit code $SERVE_RC"
  wait "$STRANGER" || fail "the stranger failed"
  grep -Eq '^stranger sent [1-9][0-9]+ answers 0$' "$TMP/stranger.out" || fail "the stranger was answered: $(cat "$TMP/stranger.out")"
  grep -q 'sim c4g: completed' "$TMP/sim.out" || fail "the controller's program did not complete: $(cat "$TMP/sim.out")"
}

# 1. Text report.
start_c4g_serve --app echo
stranger_after_init serve.out
run_sim_c4g "$SCENARIO"
check_run
grep -q "Safety: none" "$TMP/serve.out" || fail "a safety fault was latched"
grep -Eq "foreign datagrams ignored [1-9][0-9]* \(last from 127\.0\.0\.1:[0-9]+\)" "$TMP/serve.out" \
  || fail "no foreign count in the report"
grep -Eq "^status .*\| foreign [1-9]" "$TMP/serve.out" || fail "no foreign count in the status lines"
grep -Eq "Packets [0-9]+ \(init 1, cyclic [0-9]+\), protocol errors 0," "$TMP/serve.out" \
  || fail "the stranger's packets reached the session: $(grep '^Packets' "$TMP/serve.out")"
grep -q "^session: controller 127.0.0.1:" "$TMP/serve.out" || fail "the session's controller is not named"

# 2. JSON report: stdout is one JSON document, the lines are on stderr.
rm -f "$TMP/serve.out" "$TMP/serve.err"
"$AXON" c4g serve --listen 127.0.0.1:0 --status-interval 0.5 --app echo --json >"$TMP/serve.out" 2>"$TMP/serve.err" &
SERVE_PID=$!
PIDS+=($SERVE_PID)
C4G_PORT=$(wait_for_line "$TMP/serve.err" '^listening c4g ' | sed 's/.*://')
stranger_after_init serve.err
run_sim_c4g "$SCENARIO"
check_run
python3 - "$TMP/serve.out" <<'PY' || fail "JSON report: $(cat "$TMP/serve.out")"
import json, sys
j = json.load(open(sys.argv[1]))
assert j["session"]["foreign"] > 0, j["session"]
assert j["session"]["last_foreign_source"].startswith("127.0.0.1:"), j["session"]
assert j["session"]["sessions"] == 1, j["session"]
assert j["init_packets"] == 1 and j["protocol_errors"] == 0, j
assert j["safety_fault"] == "none", j["safety_fault"]
PY
grep -h "foreign datagrams ignored\|^stranger" "$TMP/serve.out" "$TMP/stranger.out" >&2 || true
echo ok
