#!/usr/bin/env bash
# Runs every soak program of a build for MINUTES each, one after the other (they measure rates and
# memory: never two at once), and fails if any did. Usage: soak/run.sh BUILD_DIR [MINUTES] [SEED]
set -uo pipefail
build=${1:?usage: soak/run.sh BUILD_DIR [MINUTES] [SEED]}
minutes=${2:-30}
seed=${3:-1}
status=0
found=0
for prog in "$build"/soak/axon_soak_*; do
  [ -x "$prog" ] || continue
  found=1
  echo "=== $(basename "$prog") --minutes $minutes --seed $seed" >&2
  "$prog" --minutes "$minutes" --seed "$seed" || status=1
done
[ $found = 1 ] || { echo "soak/run.sh: no soak programs in $build/soak (build first)" >&2; exit 1; }
exit $status
