#!/usr/bin/env bash
# After a failed ctest run: what each failed test said, short, as the last lines of the output (a CI
# log is often read from its end, where ctest leaves only the list of names).
# usage: scripts/test-failures.sh BUILD_DIR
set -uo pipefail
dir="${1:?usage: test-failures.sh BUILD_DIR}/Testing/Temporary"
[ -f "$dir/LastTestsFailed.log" ] && [ -f "$dir/LastTest.log" ] || exit 0
echo
echo "=== what the failed tests said (their last lines; full output above and in $dir/LastTest.log)"
while IFS=: read -r _ name; do
  [ -n "$name" ] || continue
  # LastTest.log: each test's output sits between its "Testing: NAME" header and "Test time".
  out=$(awk -v t="$name" '
    $0 ~ "Testing: " t "$" { found = 1; next }
    found && /^Output:$/ { on = 1; next }
    on && /^Test time = / { exit }
    on && /^(<end of output>|-+)$/ { next }
    on { print }' "$dir/LastTest.log")
  last=$(printf '%s\n' "$out" | grep -v '^$' | tail -n 8 | cut -c1-240)
  echo "--- $name"
  # the first failure lines, when the last lines do not already show them, then the last lines
  printf '%s\n' "$out" | grep -E '^(FAIL|\[  FAILED  \]|.*Failure$)' | head -n 3 | cut -c1-240 | grep -vxF -e "$last"
  printf '%s\n' "$last"
done <"$dir/LastTestsFailed.log"
exit 0
