#!/usr/bin/env bash
# Runs every benchmark executable built from bench/*.cpp, then bench/python_front_end.py, and collects
# their BENCH summary lines.
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
# The actor over a real broker (needs rabbitmq-server and python3-pika).
if [ -x /usr/lib/rabbitmq/bin/rabbitmq-server ]; then
  echo "== actor_roundtrip"
  out=$(/usr/bin/python3 "$here/actor_roundtrip.py" "$build" 2>&1 | tee /dev/stderr)
  summary+=("$(grep "^BENCH " <<<"$out" | tail -n 1)")
fi
# The Python front end's cost (needs the Python module: AXON_PYTHON=ON, the default with pybind11).
if [ -d "$build/python/axon" ]; then
  echo "== python_front_end"
  out=$(/usr/bin/python3 "$here/python_front_end.py" "$build" 2>&1 | tee /dev/stderr)
  summary+=("$(grep '^BENCH ' <<<"$out" | tail -n 1)")
fi
echo
echo "== summary"
printf '%s\n' "${summary[@]}"
