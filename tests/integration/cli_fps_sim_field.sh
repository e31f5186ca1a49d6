#!/usr/bin/env bash
# What host software in service expects of the focal-plane simulator, between processes:
#  - each gateway emulator at its own address on one shared port (--bind counts up, or the layout's
#    own addresses with --bind layout), so a host configured like an installation works unchanged;
#  - a subset move started by one START_TRAJECTORY broadcast, after which the host waits for every
#    robot's acceptance (robots without a trajectory accept and stay; --start-without-trajectory
#    refuse brings back the old answer, code 2, which fails such a host).
source "$(dirname "$0")/lib.sh"
HELPERS="$(cd "$(dirname "$0")" && pwd)/helpers"
free_port() { /usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }

# 1. --bind 127.0.0.11 --port P: gateway 1 at 127.0.0.11:P, gateway 2 at 127.0.0.12:P.
PORT=$(free_port)
start_plane counted "$SMALL_PLANE" --bind 127.0.0.11 --port "$PORT"
grep -q "^listening gateway 1 127.0.0.11:$PORT " "$TMP/counted.out" || fail "gateway 1 not at 127.0.0.11:$PORT"
grep -q "^listening gateway 2 127.0.0.12:$PORT " "$TMP/counted.out" || fail "gateway 2 not at 127.0.0.12:$PORT"
grep -q "127.0.0.11:$PORT" "$TMP/counted.yaml" && grep -q "127.0.0.12:$PORT" "$TMP/counted.yaml" \
  || fail "--write-layout does not have the addresses used: $(cat "$TMP/counted.yaml")"

# 2. The field host's subset move: robot 1 moves, robots 2, 3, 7, 8, 9 have nothing loaded.
/usr/bin/python3 "$HELPERS/field_host_subset_move.py" 1 10 "127.0.0.11:$PORT" "127.0.0.12:$PORT" \
  >"$TMP/field.out" 2>&1 || fail "field host subset move failed: $(cat "$TMP/field.out")"
grep -q "^found robots 1,2,3,7,8,9 on 2 gateways" "$TMP/field.out" || fail "discovery: $(cat "$TMP/field.out")"
grep -q "^done: robot 1 " "$TMP/field.out" || fail "no move: $(cat "$TMP/field.out")"

# 3. axon's own host, unchanged, on the written layout (same addresses), and a subset move by file.
"$AXON" fps plane --layout "$TMP/counted.yaml" check >"$TMP/check.out" 2>"$TMP/check.err" || fail "plane check exited with $?"
cat >"$TMP/one.yaml" <<'YAML'
2: {alpha: [[5, 1.0]]}
YAML
"$AXON" fps --bus "cannet://127.0.0.11:$PORT/1" move --trajectory "$TMP/one.yaml" >"$TMP/move.out" 2>"$TMP/move.err" \
  || fail "axon fps move of robot 2 exited with $?"
kill "${PIDS[-1]}"; wait "${PIDS[-1]}" 2>/dev/null || true

# 4. The same plane with the layout's own addresses (--bind layout): the host uses the very file the
#    simulator was started with.
PORT2=$(free_port)
sed -e "s/\"127.0.0.1:1\", sextant: 1/\"127.0.0.21:$PORT2\", sextant: 1/" \
    -e "s/\"127.0.0.1:1\", sextant: 2/\"127.0.0.22:$PORT2\", sextant: 2/" "$SMALL_PLANE" >"$TMP/installation.yaml"
start_plane site "$TMP/installation.yaml" --bind layout
grep -q "^listening gateway 2 127.0.0.22:$PORT2 " "$TMP/site.out" || fail "gateway 2 not at its layout address"
"$AXON" fps plane --layout "$TMP/installation.yaml" check >"$TMP/check2.out" 2>"$TMP/check2.err" \
  || fail "plane check on the site layout exited with $?: $(cat "$TMP/check2.err")"
kill "${PIDS[-1]}"; wait "${PIDS[-1]}" 2>/dev/null || true

# 5. The old answer (code 2 from robots with nothing loaded) fails the field host, as seen in service.
start_plane refusing "$SMALL_PLANE" --bind 127.0.0.31 --port "$PORT" --start-without-trajectory refuse
if /usr/bin/python3 "$HELPERS/field_host_subset_move.py" 1 10 "127.0.0.31:$PORT" "127.0.0.32:$PORT" \
  >"$TMP/refused.out" 2>&1; then fail "field host succeeded against refusing robots: $(cat "$TMP/refused.out")"; fi
grep -q "^FAIL: START_TRAJECTORY not accepted by every robot (2: code 2, 3: code 2, 7: code 2" "$TMP/refused.out" \
  || fail "unexpected refusal report: $(cat "$TMP/refused.out")"

# 6. Bad values are usage errors (exit 2), not a half-started plane.
set +e
"$AXON" sim fps --layout "$SMALL_PLANE" --firmware 04.00.09 --duration 1 >"$TMP/old.out" 2>"$TMP/old.err"; rc=$?
set -e
[ "$rc" -ne 0 ] || fail "firmware 04.00.09 accepted"
grep -q "not modelled" "$TMP/old.err" || fail "no reason for refusing 04.00.09: $(cat "$TMP/old.err")"
echo "PASS"
