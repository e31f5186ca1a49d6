#!/usr/bin/env bash
# `axon demo` (what `make run` shows a new user) runs every family against its simulator and says
# what happened: CAN round trips on three transports, 500 positioners planned and moved, the c4g
# robot program against the server. Into a file its progress has no carriage returns.
source "$(dirname "$0")/lib.sh"
"$AXON" demo >"$TMP/demo.out" 2>"$TMP/demo.err" || fail "demo exited with $?"
grep -q '200/200 answered' "$TMP/demo.out" || fail "CAN round trips"
grep -q 'completed: 500 robots at their targets' "$TMP/demo.out" || fail "fps move"
grep -q 'verified: 500 of 500 robots at their planned end' "$TMP/demo.out" || fail "fps verification"
grep -q 'program completed' "$TMP/demo.out" || fail "c4g program"
grep -q 'mode 501 (driving_on) -> 4 (mode4)' "$TMP/demo.out" || fail "c4g mode 4 not entered"
grep -q 'plain UDP echo p50' "$TMP/demo.out" || fail "c4g echo baseline"
if grep -q $'\r' "$TMP/demo.out"; then fail "carriage returns in a file"; fi
echo "PASS"
