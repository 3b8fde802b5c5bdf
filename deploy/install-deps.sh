#!/usr/bin/env bash
# Installs the Debian 12 packages the farm builds and tests with. Idempotent: a machine that has
# them all installs nothing and does not touch the network.
set -euo pipefail

packages=(
  build-essential cmake ninja-build ccache pkg-config git
  libembree-dev libtbb-dev
  libopenexr-dev libopenimageio-dev
  libgrpc++-dev protobuf-compiler-grpc libprotobuf-dev protobuf-compiler
  libpugixml-dev libtinyobjloader-dev libassimp-dev libopenvdb-dev libboost-dev zlib1g-dev libcli11-dev libspdlog-dev nlohmann-json3-dev libsqlite3-dev libzstd-dev libssl-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libcpp-httplib-dev chromium
  iproute2 openssl python3-grpcio python3-protobuf python3-numpy python3-openimageio python3-matplotlib
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if ((${#missing[@]} == 0)); then
  exit 0
fi

echo "deploy/install-deps.sh: installing ${missing[*]}" >&2
sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -q
$sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
