#!/usr/bin/env bash
# Long CAN tool runs: a replay across a long gap in its log says that it waits and stops on the
# first SIGINT/SIGTERM (exit 128+N); a dump's log rotates at its size limit (FILE, FILE.1, ...).
source "$(dirname "$0")/lib.sh"
start_bridge --listen 127.0.0.1:0
bus="socketcand://127.0.0.1:$SCD_PORT/vcan0"

# 1. Replay: 30 s between the second and third frame.
cat >"$TMP/gap.log" <<'LOG'
(1700000000.000000) can0 100#01
(1700000000.100000) can0 101#02
(1700000030.100000) can0 102#03
LOG
for sig in INT TERM; do
  rm -f "$TMP/replay.err"
  "$AXON" can replay --bus "$bus" "$TMP/gap.log" >"$TMP/replay.out" 2>"$TMP/replay.err" &
  r=$!; PIDS+=($r)
  # The gap less the time since the first frame went out (29.9 s on a loaded machine).
  wait_for_line "$TMP/replay.err" 'waiting (29\.[5-9]|30\.0) s for the next frame \(line 3\)' 10 >/dev/null
  kill -s "$sig" "$r"
  # One signal must do: the replay ends well before the gap would have passed.
  for _ in $(seq 1 100); do kill -0 "$r" 2>/dev/null || break; sleep 0.05; done
  kill -0 "$r" 2>/dev/null && fail "replay still running 5 s after SIG$sig"
  set +e; wait "$r"; rc=$?; set -e
  want=$([ "$sig" = INT ] && echo 130 || echo 143)
  [ "$rc" -eq "$want" ] || fail "replay stopped by SIG$sig exited $rc, expected $want"
  grep -q "stopped by SIG$sig" "$TMP/replay.err" || fail "no stop message: $(cat "$TMP/replay.err")"
  grep -q "2 frames sent" "$TMP/replay.err" || fail "replay did not report the frames it sent: $(cat "$TMP/replay.err")"
done

# 2. Dump with a 100-byte limit and 3 old files kept; frames 100#00 .. 113#13 in order.
frames=$(for i in $(seq 0 19); do printf '%03X#%02X ' $((0x100 + i)) "$i"; done)
"$AXON" can dump --bus "$bus" --count 20 --timeout 20 --no-print --log "$TMP/rot.log" --log-max-size 100 --log-keep 3 \
  >"$TMP/dump.out" 2>"$TMP/dump.err" &
d=$!; PIDS+=($d)
wait_for_line "$TMP/dump.err" 'receiving on' >/dev/null
# shellcheck disable=SC2086
"$AXON" can send --bus "$bus" $frames >"$TMP/send.out" 2>"$TMP/send.err" || fail "send failed"
wait "$d" || fail "dump exited with $?"
for f in rot.log rot.log.1 rot.log.2 rot.log.3; do
  [ -f "$TMP/$f" ] || fail "no $f: $(ls "$TMP")"
  size=$(stat -c %s "$TMP/$f")
  [ "$size" -le 100 ] || fail "$f has $size bytes, over the 100-byte limit"
done
[ -f "$TMP/rot.log.4" ] && fail "more than 3 old files kept"
# Oldest to newest: rot.log.3, .2, .1, rot.log; consecutive frames ending with the last one sent.
ids=$(cat "$TMP/rot.log.3" "$TMP/rot.log.2" "$TMP/rot.log.1" "$TMP/rot.log" | awk '{split($3, a, "#"); print a[1]}' | xargs)
/usr/bin/python3 - "$ids" <<'PY' || fail "rotated files out of order: $ids"
import sys
ids = [int(x, 16) for x in sys.argv[1].split()]
assert ids[-1] == 0x113 and ids == list(range(ids[0], 0x114)), ids
PY
echo "PASS"
