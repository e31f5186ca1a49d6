#!/usr/bin/env bash
# Runs every fuzz target for a few seconds from its seed corpus (fuzz/corpus/<name>/); any crash
# fails. Targets run side by side, JOBS at a time (default: the number of cores), each with its own
# copy of the seeds; their reports are printed in the order of the targets.
set -euo pipefail
build=${1:-build/asan}
seconds=${2:-10}
jobs=${JOBS:-$(nproc)}
here=$(cd "$(dirname "$0")" && pwd)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

run_one() {  # name: fuzz one target; its log in $out/<name>.log, its exit status in $out/<name>.rc
  local name=$1 work="$out/$1.corpus" status=0
  mkdir -p "$work"
  [ -d "$here/corpus/$name" ] && cp -r "$here/corpus/$name"/. "$work"/
  "$build/fuzz/fuzz_$name" -max_total_time="$seconds" -print_final_stats=1 "$work" >"$out/$name.log" 2>&1 ||
    status=$?
  echo "$status" >"$out/$name.rc"
}

names=()
for src in "$here"/*.cpp; do names+=("$(basename "$src" .cpp)"); done
echo "fuzz: ${#names[@]} targets, ${seconds}s each, $jobs at a time"
for name in "${names[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$jobs" ]; do wait -n || true; done
  run_one "$name" &
done
wait

failed=0
for name in "${names[@]}"; do
  status=$(cat "$out/$name.rc")
  echo "fuzz: $name"
  grep -E 'stat::number_of_executed_units|ERROR|SUMMARY' "$out/$name.log" || true
  if [ "$status" -ne 0 ]; then
    tail -n 40 "$out/$name.log" >&2
    echo "fuzz: $name FAILED (exit $status)" >&2
    failed=1
  fi
done
[ "$failed" -eq 0 ] || exit 1
echo "fuzz: all targets clean"
