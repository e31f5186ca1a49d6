#!/usr/bin/env bash
# Mode 0 against the simulator in another process: the monitor app logs drives on and the end of
# the exchange (504), records a capture that tcpdump and init-info read, and exits by itself.
source "$(dirname "$0")/lib.sh"
skip_without_sim_c4g
# The robot program of both runs: drives on, a short move in mode 0, the end of the exchange.
PROGRAM="steps:
  - drive_on
  - move: {arm: 1, deg: [5, 0, 0, 0, 0, 0], duration: 0.3}
  - delay: 0.1
  - exit_open"
start_c4g_serve --app monitor --pcap "$TMP/run.pcap" --csv "$TMP/moni.csv" --moni 20
run_sim_c4g "$PROGRAM"
[ "$SIM_RC" = 0 ] || fail "simulator exit code $SIM_RC"
wait_serve
[ "$SERVE_RC" = 0 ] || fail "serve exit code $SERVE_RC"
grep -q "arm 1: drives on" "$TMP/serve.out" || fail "no drives-on event"
grep -q "controller ended the exchange (504)" "$TMP/serve.out" || fail "504 not seen"
grep -q "Worst cycle time" "$TMP/serve.out" || fail "no timing report"
[ "$(head -1 "$TMP/moni.csv" | cut -d, -f3)" = "a1_c4g_d1" ] || fail "moni 20 header"
[ "$(wc -l <"$TMP/moni.csv")" -gt 100 ] || fail "moni CSV too short"
"$AXON" c4g init-info --from-pcap "$TMP/run.pcap" >"$TMP/info.out" || fail "init-info"
grep -q "open axis 6 = arm 1 axis 6" "$TMP/info.out" || fail "init-info content"
if command -v tcpdump >/dev/null; then
  # Not piped into grep -q: grep quitting early would SIGPIPE tcpdump and fail the pipeline (pipefail).
  tcpdump -nn -r "$TMP/run.pcap" >"$TMP/tcpdump.txt" 2>/dev/null || fail "tcpdump cannot read the capture"
  grep -q "UDP, length 1200" "$TMP/tcpdump.txt" || fail "tcpdump does not show the initialization packet"
fi

# The same with size limits: the recordings rotate (FILE.1, FILE.2 ...), every CSV file starts with
# the title line, every capture is whole, and the report counts the rotations.
start_c4g_serve --app monitor --pcap "$TMP/rot.pcap" --pcap-max-size 64k --csv "$TMP/rot.csv" --moni 20 --csv-max-size 8k
run_sim_c4g "$PROGRAM"
[ "$SIM_RC" = 0 ] || fail "simulator exit code $SIM_RC (rotation run)"
wait_serve
[ -f "$TMP/rot.pcap.1" ] && [ -f "$TMP/rot.csv.1" ] || fail "no rotated files: $(ls "$TMP")"
for f in "$TMP"/rot.csv*; do
  [ "$(head -1 "$f" | cut -d, -f3)" = "a1_c4g_d1" ] || fail "$f does not start with the title line"
  [ "$(stat -c %s "$f")" -le 8192 ] || fail "$f passes the size limit"
done
for f in "$TMP"/rot.pcap*; do [ "$(stat -c %s "$f")" -le 65536 ] || fail "$f passes the size limit"; done
grep -Eq "Capture .*rot.pcap: [0-9]+ written, 0 dropped, [1-9][0-9]* rotations, 0 write failures" "$TMP/serve.out" \
  || fail "capture rotations not reported: $(grep Capture "$TMP/serve.out")"
if command -v tcpdump >/dev/null; then
  tcpdump -nn -r "$TMP/rot.pcap.1" >"$TMP/tcpdump1.txt" 2>/dev/null || fail "tcpdump cannot read a rotated capture"
fi
echo ok
