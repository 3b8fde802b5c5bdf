#!/usr/bin/env bash
# Installs the Debian 12 packages the farm builds and tests with, and the one npm package its
# deploy test needs. Idempotent: a machine that has them all installs nothing and does not
# touch the network.
#
#   deploy/install-deps.sh               # build and test (this machine, CI)
#   deploy/install-deps.sh --build-only  # build only: no browser, no Python, no npm (the image)
set -euo pipefail

build_only=false
if [ "${1:-}" = "--build-only" ]; then build_only=true; fi

packages=(
  build-essential cmake ninja-build ccache pkg-config git
  libembree-dev libtbb-dev
  libopenexr-dev libopenimageio-dev
  libgrpc++-dev protobuf-compiler-grpc libprotobuf-dev protobuf-compiler
  libpugixml-dev libtinyobjloader-dev libassimp-dev libopenvdb-dev libboost-dev zlib1g-dev libcli11-dev libspdlog-dev nlohmann-json3-dev libsqlite3-dev libzstd-dev libssl-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libcpp-httplib-dev
)
if ! $build_only; then
  packages+=(
    chromium iproute2 openssl
    python3-grpcio python3-protobuf python3-yaml python3-numpy python3-openimageio python3-matplotlib
  )
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if ((${#missing[@]} > 0)); then
  echo "deploy/install-deps.sh: installing ${missing[*]}" >&2
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -q
  $sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# The Kubernetes schemas the deploy test validates the manifests against (npm registry, with
# the machine's Node.js), under deploy/.npm (ignored by git).
npm_dir="$(cd "$(dirname "$0")" && pwd)/.npm"
if ! $build_only && [ ! -f "$npm_dir/node_modules/kubernetes-models/package.json" ]; then
  echo "deploy/install-deps.sh: installing kubernetes-models into $npm_dir" >&2
  mkdir -p "$npm_dir"
  npm install --prefix "$npm_dir" --no-audit --no-fund --loglevel=error kubernetes-models@4.5.1
fi
