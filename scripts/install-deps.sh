#!/usr/bin/env bash
# Installs every Debian package that axon's build, tests, fuzzers and benchmarks need.
# Idempotent: when everything is present it only checks and returns (well under a second).
# Run as root or as a user with sudo.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  clang libclang-rt-dev            # libFuzzer targets and clang sanitizer runtimes
  libboost-dev                    # Asio (C++20 coroutines), Beast (the web server), Outcome, lockfree
  libfmt-dev libspdlog-dev libcli11-dev libyaml-cpp-dev nlohmann-json3-dev
  libeigen3-dev zlib1g-dev libmodbus-dev libpcap-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  python3 python3-can             # interoperability tests against python-can
  pybind11-dev python3-dev python3-pytest python3-numpy   # the Python module axon and its tests
  tcpdump                         # checks that pcap captures decode
  chromium chromium-driver python3-selenium   # the pages tested in headless Chromium (tests/integration/web_*.py)
  prometheus                      # promtool checks /metrics (docs/dashboard.md)
  libjs-chart.js                  # charts of the blmc and c4g pages, served from /usr/share/javascript
  librabbitmq-dev                 # the AMQP client under `axon actor` and `axon tell` (src/axon/actor)
  rabbitmq-server python3-pika python3-jsonschema  # the actor tests: a private broker, an independent client, the keyword schema
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then
    SUDO="sudo"
  else
    echo "install-deps: missing packages (${missing[*]}) and not root; run this script as root" >&2
    exit 1
  fi
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
