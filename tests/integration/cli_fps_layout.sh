#!/usr/bin/env bash
# Layout files: the committed default layout is what `axon fps layout generate` writes; `show`
# summarises it; `check` finds the benchtop robots on a simulated gateway, then reports a missing
# and an unexpected robot (exit 1) when the simulator's robots differ from the layout.
source "$(dirname "$0")/lib.sh"
DATA="$(cd "$(dirname "$0")/../../data/layouts" && pwd)"

"$AXON" fps layout generate -o "$TMP/default.yaml" 2>"$TMP/gen.err" || fail "generate exited with $?"
cmp -s "$TMP/default.yaml" "$DATA/default.yaml" || fail "data/layouts/default.yaml differs from the generator's output"

"$AXON" fps layout show "$DATA/default.yaml" >"$TMP/show.out" 2>"$TMP/show.err" || fail "show exited with $?"
grep -q '500 robots, 61 fiducials' "$TMP/show.out" || fail "show: counts"
grep -q 'robots per sextant: 1:83 2:83 3:84 4:83 5:83 6:84' "$TMP/show.out" || fail "show: per sextant"
"$AXON" fps layout show --json "$DATA/default.yaml" >"$TMP/show.json" 2>"$TMP/show.err" || fail "show --json exited with $?"
/usr/bin/python3 - "$TMP/show.json" <<'PY' || fail "show --json is not what was expected"
import json, sys
j = json.load(open(sys.argv[1]))
assert j["robots"] == 500 and len(j["buses"]) == 24, j
assert all(20 <= n <= 21 for n in j["buses"].values()), j["buses"]
assert j["fibres"]["apogee"] == 300, j["fibres"]
PY

# A typo in a layout is an error naming the line.
printf 'gateways: [{id: 1}]\nrobots:\n  - {id: 1, x: 0, y: 0, sextant: 1, gateway: 1, buss: 1}\n' >"$TMP/typo.yaml"
if "$AXON" fps layout show "$TMP/typo.yaml" >"$TMP/typo.out" 2>"$TMP/typo.err"; then fail "typo accepted"; fi
grep -q 'typo.yaml:3:.*buss' "$TMP/typo.err" || fail "typo error does not name line 3 and the key"

start_sim_fps --robots 1-6 --gateway 127.0.0.1:0
"$AXON" fps --gateway "127.0.0.1:$SIM_CANNET_PORT" layout check --window 2 "$DATA/benchtop.yaml" >"$TMP/check.out" 2>"$TMP/check.err" \
  || fail "check of the benchtop layout exited with $?"
grep -q '^OK: 6 matched' "$TMP/check.out" || fail "check did not match 6 robots"
kill "$SIM_PID"; wait "$SIM_PID" 2>/dev/null || true

start_sim_fps --robots 1-5,9 --gateway 127.0.0.1:0
if "$AXON" fps --gateway "127.0.0.1:$SIM_CANNET_PORT" layout check --window 2 --json "$DATA/benchtop.yaml" >"$TMP/bad.json" 2>"$TMP/bad.err"; then
  fail "check with a missing robot exited 0"
fi
/usr/bin/python3 - "$TMP/bad.json" <<'PY' || fail "check --json did not report 6 missing and 9 unexpected"
import json, sys
j = json.load(open(sys.argv[1]))
assert not j["ok"], j
assert j["missing"] == [6], j
assert [u["id"] for u in j["unexpected"]] == [9], j
assert j["matched"] == [1, 2, 3, 4, 5], j
PY
echo "PASS"
