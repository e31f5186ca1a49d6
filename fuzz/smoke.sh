#!/usr/bin/env bash
# Runs fuzz targets from their seed corpora (fuzz/corpus/<name>/); any crash fails. Targets run
# side by side, JOBS at a time (default: the number of cores); their reports are printed in the
# order of the targets, each ending with one line:
#   FUZZ <name> seconds=... execs=... cov=... ft=... corpus=... result=pass|FAIL
# CI runs every target a few seconds (make fuzz-smoke); a long campaign (make fuzz-long) runs them
# for 30 minutes each and keeps what they found.
#   FUZZ_TARGETS  names to run (default: every fuzz/*.cpp)
#   FUZZ_WORK     a folder whose <name>/ keeps each target's corpus from run to run (default: a
#                 fresh copy of the seeds, removed afterwards)
set -euo pipefail
build=${1:-build/asan}
seconds=${2:-10}
jobs=${JOBS:-$(nproc)}
here=$(cd "$(dirname "$0")" && pwd)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

run_one() {  # name: fuzz one target; its log in $out/<name>.log, its exit status in $out/<name>.rc
  local name=$1 work="${FUZZ_WORK:-$out}/$1.corpus" status=0
  mkdir -p "$work"
  [ -d "$here/corpus/$name" ] && cp -r "$here/corpus/$name"/. "$work"/
  "$build/fuzz/fuzz_$name" -max_total_time="$seconds" -print_final_stats=1 -artifact_prefix="$out/$name-" \
    "$work" >"$out/$name.log" 2>&1 || status=$?
  echo "$status" >"$out/$name.rc"
}

summary() {  # name status: the target's one-line figures from its log
  local name=$1 status=$2 log="$out/$1.log" last
  last=$(grep -E '^#[0-9]+' "$log" | tail -n 1 || true)
  printf 'FUZZ %s seconds=%s execs=%s cov=%s ft=%s corpus=%s result=%s\n' "$name" "$seconds" \
    "$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")" \
    "$(grep -oE 'cov: [0-9]+' <<<"$last" | grep -oE '[0-9]+' || echo 0)" \
    "$(grep -oE 'ft: [0-9]+' <<<"$last" | grep -oE '[0-9]+' || echo 0)" \
    "$(grep -oE 'corp: [0-9]+' <<<"$last" | grep -oE '[0-9]+' || echo 0)" \
    "$([ "$status" -eq 0 ] && echo pass || echo FAIL)"
}

names=()
if [ -n "${FUZZ_TARGETS:-}" ]; then
  read -r -a names <<<"$FUZZ_TARGETS"
else
  for src in "$here"/*.cpp; do names+=("$(basename "$src" .cpp)"); done
fi
echo "fuzz: ${#names[@]} targets, ${seconds}s each, $jobs at a time"
for name in "${names[@]}"; do
  [ -x "$build/fuzz/fuzz_$name" ] || { echo "fuzz: no target $build/fuzz/fuzz_$name" >&2; exit 2; }
  while [ "$(jobs -rp | wc -l)" -ge "$jobs" ]; do wait -n || true; done
  run_one "$name" &
done
wait

failed=0
for name in "${names[@]}"; do
  status=$(cat "$out/$name.rc")
  grep -E 'ERROR|SUMMARY' "$out/$name.log" || true
  summary "$name" "$status"
  if [ "$status" -ne 0 ]; then
    tail -n 40 "$out/$name.log" >&2
    for crash in "$out/$name"-*; do
      [ -e "$crash" ] && cp "$crash" "${FUZZ_WORK:-.}/" && echo "fuzz: kept the input $(basename "$crash")" >&2
    done
    echo "fuzz: $name FAILED (exit $status)" >&2
    failed=1
  fi
done
[ "$failed" -eq 0 ] || exit 1
echo "fuzz: all targets clean"
