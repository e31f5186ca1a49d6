#!/usr/bin/env bash
# Runs every fuzz target for a few seconds from its seed corpus (fuzz/corpus/<name>/); any crash fails.
set -euo pipefail
build=${1:-build/fuzz}
seconds=${2:-10}
here=$(cd "$(dirname "$0")" && pwd)
for src in "$here"/*.cpp; do
  name=$(basename "$src" .cpp)
  work=$(mktemp -d)
  seeds="$here/corpus/$name"
  [ -d "$seeds" ] && cp -r "$seeds"/. "$work"/
  echo "fuzz: $name for ${seconds}s"
  status=0
  "$build/fuzz/fuzz_$name" -max_total_time="$seconds" -print_final_stats=1 "$work" >"$work.log" 2>&1 || status=$?
  grep -E 'stat::number_of_executed_units|ERROR|SUMMARY' "$work.log" || true
  [ "$status" -eq 0 ] || tail -n 40 "$work.log" >&2
  rm -f "$work.log"
  rm -rf "$work"
  if [ "$status" -ne 0 ]; then echo "fuzz: $name FAILED" >&2; exit 1; fi
done
echo "fuzz: all targets clean"
