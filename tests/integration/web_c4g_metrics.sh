#!/usr/bin/env bash
# `axon c4g serve --app stream --mode 4 --http 127.0.0.1:0` answering `axon sim c4g`: the server's
# web page and /metrics, read after the run (--http-linger keeps them up).
#   1. /metrics passes Prometheus's own linter (`promtool check metrics`) and has the c4g families:
#      cycles, late replies, drive-off replies, the processing-time and period histograms (one
#      observation per cycle, one per period), the modes per axis, the app's phase;
#   2. /api/c4g/state agrees with the server's own report (cycles, the app done, no fault) and its
#      receive-to-send histogram counts every cycle; /api/c4g/info has the modes' labels; the index
#      lists the c4g page and the page is served.
source "$(dirname "$0")/lib.sh"
skip_without_sim_c4g
command -v promtool >/dev/null || fail "promtool not found (Debian's prometheus package; scripts/install-deps.sh)"
cat >"$TMP/traj.csv" <<CSV
# units: deg
t,j1,j2,j3,j4,j5,j6
0,0,0,0,0,0,0
0.4,4,-2,1,0,5,0
0.8,0,0,0,0,0,0
CSV
start_c4g_serve --app stream --file "$TMP/traj.csv" --mode 4 --relative --http 127.0.0.1:0 --http-linger 30
URL=http://$(wait_for_line "$TMP/serve.out" '^listening http ' | awk '{print $3}')
run_sim_c4g "steps:
  - drive_on
  - go_open: {type: A, mode: 4, arms: [1]}
  - wait_for_pc: {timeout: 10}
  - exit_open"
[ "$SIM_RC" = 0 ] || { cat "$TMP/sim.err" >&2; fail "simulator exit code $SIM_RC"; }
wait_for_line "$TMP/serve.out" '^Cycles ' 20 >/dev/null  # the run's report: the page lingers from here

# 1. Prometheus's linter, then the families.
curl -sSf "$URL/metrics" >"$TMP/metrics.txt" || fail "GET /metrics"
promtool check metrics <"$TMP/metrics.txt" >"$TMP/promtool.out" 2>&1 || { cat "$TMP/promtool.out" >&2; fail "promtool check metrics"; }
for name in axon_c4g_cycles_total axon_c4g_late_replies_total axon_c4g_unanswered_packets_total \
            axon_c4g_drive_off_replies_total axon_c4g_following_error_replies_total axon_c4g_safety_faults_total \
            axon_c4g_cycle_time_seconds axon_c4g_inter_packet_period_seconds axon_c4g_reply_deadline_seconds \
            axon_c4g_axis_mode axon_c4g_drives_on axon_c4g_app_phase axon_c4g_controller_errors_total \
            axon_web_http_requests_total; do
  grep -q "^# TYPE $name " "$TMP/metrics.txt" || fail "no $name in /metrics"
done
grep -q '^# TYPE axon_c4g_cycle_time_seconds histogram$' "$TMP/metrics.txt" || fail "the processing time is not a histogram"
value() { awk -v n="$1" '$1 == n {print $2}' "$TMP/metrics.txt"; }
cycles=$(value axon_c4g_cycles_total)
timed=$(value axon_c4g_cycle_time_seconds_count)
periods=$(value axon_c4g_inter_packet_period_seconds_count)
[ "$cycles" -gt 300 ] || fail "only $cycles cycles in a run of about a second"
# Every datagram answered is timed (the initialization packet too), every gap between two is a period.
[ "$timed" -eq $((cycles + 1)) ] || fail "$timed processing times for $cycles cycles and the initialization packet"
[ "$periods" -eq "$cycles" ] || fail "$periods periods for $((cycles + 1)) packets"
grep -q '^axon_c4g_reply_deadline_seconds 0.0005$' "$TMP/metrics.txt" || fail "the deadline is not the manual's 500 us"
grep -q '^axon_c4g_app_phase{phase="done"} 1$' "$TMP/metrics.txt" || fail "the app not done"
grep -q '^axon_c4g_safety_faulted 0$' "$TMP/metrics.txt" || fail "a safety fault"

# 2. The JSON endpoints, the index and the page.
curl -sSf "$URL/api/c4g/info" >"$TMP/info.json" || fail "GET /api/c4g/info"
/usr/bin/python3 - "$URL" "$TMP/info.json" "$cycles" <<'PY' || fail "/api/state"
import json, sys, urllib.request
with urllib.request.urlopen(sys.argv[1] + "/api/state", timeout=5) as r:
    state = json.load(r)["c4g"]
info = json.load(open(sys.argv[2]))
assert state["counters"]["cyclic"] == int(sys.argv[3]), state["counters"]
assert state["app"]["name"] == "stream" and state["app"]["phase"] == "done", state["app"]
assert state["server"]["state"] == "stopped" and state["server"]["period_ms"] == 2, state["server"]
assert state["safety"]["fault"] == "none", state["safety"]
assert len(state["axes"]) == 6 and all(a["arm"] == 1 for a in state["axes"]), state["axes"]
t = state["timing"]
assert sum(t["cycle_hist"]["counts"]) == t["cycles"] == int(sys.argv[3]) + 1, t
assert t["deadline_us"] == 500, t
texts = [e["text"] for e in state["events"]]
assert any("-> 4 (mode4)" in x for x in texts), texts
labels = {m["code"]: m["label"] for m in info["modes"]}
assert labels[4] == "4" and labels[14] == "4'" and labels[10] == "0'", labels
PY
get() { curl -sSf "$URL$1" >"$TMP/body" || fail "GET $1"; }
get / && grep -q 'href="/c4g.html"' "$TMP/body" || fail "the index does not list the c4g page"
get /c4g.html && grep -q 'src="/javascript/chart.js/chart.min.js"' "$TMP/body" || fail "/c4g.html is not the page"
get /c4g.js
echo PASS
