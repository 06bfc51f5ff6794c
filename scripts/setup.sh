#!/usr/bin/env bash
# Installs what rmap needs on Debian 12; apt-get runs only when a package is missing,
# npm only when the viewer's packages (web/node_modules) are missing or older than
# web/package-lock.json.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  build-essential cmake pkg-config ninja-build
  libeigen3-dev liboctomap-dev zlib1g-dev libbz2-dev
  nlohmann-json3-dev libspdlog-dev libcli11-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libboost-dev libboost-system-dev libssl-dev
  libprotobuf-dev protobuf-compiler libsqlite3-dev libyaml-cpp-dev
  libpng-dev  # PNG raster tiles of the 2D layers
  libopencv-dev libceres-dev  # loop closure: binary features and images, the pose graph
  chromium  # the browser tests of the viewer (tests/browser)
  jq        # bench/*_matrix.sh collect the benchmarks' JSON into tables
  python3-protobuf python3-websockets  # the Python client (clients/python) and its tests
  python3-yaml  # tests/docker checks docker/compose.yaml
  openssl  # tests/integration/tls_test.cc makes its self-signed certificates with the openssl command
  clang libclang-rt-14-dev  # the libFuzzer targets (tests/fuzz, scripts/fuzz.sh): clang and its fuzzer runtime
)
# Node.js and npm fetch and test the viewer. Debian's packages only when there is no npm:
# over a NodeSource nodejs (which ships its own npm) they would conflict.
command -v npm >/dev/null || packages+=(nodejs npm)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if ((${#missing[@]})); then
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo=sudo
  echo "setup: installing ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# npm writes node_modules/.package-lock.json last, so it dates a complete install; -ot is also
# true when it does not exist.
if [ -f web/package-lock.json ] && [ web/node_modules/.package-lock.json -ot web/package-lock.json ]; then
  echo "setup: installing the viewer's packages (npm ci --prefix web)"
  npm ci --prefix web --no-audit --no-fund
fi
