#!/usr/bin/env bash
# Runs every benchmark executable built from bench/*.cpp and collects their BENCH summary lines.
set -euo pipefail
build=${1:-build/release}
here=$(cd "$(dirname "$0")" && pwd)
summary=()
for src in "$here"/*.cpp; do
  name=$(basename "$src" .cpp)
  exe="$build/bench/$name"
  [ -x "$exe" ] || { echo "bench: $exe not built" >&2; exit 1; }
  echo "== $name"
  out=$("$exe" 2>&1 | tee /dev/stderr)
  summary+=("$(grep '^BENCH ' <<<"$out" | tail -n 1)")
done
echo
echo "== summary"
printf '%s\n' "${summary[@]}"
