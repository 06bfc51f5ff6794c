#!/usr/bin/env bash
# Installs what rmap needs on Debian 12; apt-get runs only when a package is missing.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libeigen3-dev liboctomap-dev zlib1g-dev libbz2-dev
  nlohmann-json3-dev libspdlog-dev libcli11-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libboost-dev libboost-system-dev libssl-dev
  libprotobuf-dev protobuf-compiler libsqlite3-dev libyaml-cpp-dev
)

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
