#!/usr/bin/env bash
# The cycle timing figures against the controller's own period, at 1 ms and at 2 ms: `axon c4g
# serve --json` in one process, the simulated controller at --period-ms 1 / 2 in another. The
# nominal period is the initialization packet's, and the median inter-packet time sits near it (a
# fixed 1 ms nominal made a 2 ms controller look +100 % late on every packet).
source "$(dirname "$0")/lib.sh"
skip_without_sim_c4g
for period in 1 2; do
  rm -f "$TMP/serve.out" "$TMP/serve.err"
  "$AXON" c4g serve --listen 127.0.0.1:0 --app monitor --json >"$TMP/serve.out" 2>"$TMP/serve.err" &
  SERVE_PID=$!
  PIDS+=($SERVE_PID)
  C4G_PORT=$(wait_for_line "$TMP/serve.err" '^listening c4g ' | sed 's/.*://')
  run_sim_c4g "steps:
  - drive_on
  - run" --period-ms "$period" --duration 1.5
  [ "$SIM_RC" = 0 ] || fail "simulator exit code $SIM_RC at $period ms"
  kill -INT "$SERVE_PID"
  wait_serve
  python3 - "$TMP/serve.out" "$period" <<'PY' || fail "timing at $period ms: $(cat "$TMP/serve.out")"
import json, sys
t = json.load(open(sys.argv[1]))["timing"]
period = float(sys.argv[2]) * 1e-3
assert abs(t["nominal_period_s"] - period) < 1e-12, t["nominal_period_s"]
assert t["cycles"] > 300, t["cycles"]
p50 = t["inter_step_p50_s"]
assert abs(p50 - period) / period < 0.25, f"median inter-packet time {p50} s against {period} s"
lo, hi = t["jitter_percent"]
assert abs(t["jitter_s"][0] - (t["inter_packet_period_s"][0] - period)) < 1e-9, t
assert abs(lo - t["jitter_s"][0] / period * 100) < 1e-6 and abs(hi - t["jitter_s"][1] / period * 100) < 1e-6, t
assert lo > -100, lo
PY
done
echo ok
