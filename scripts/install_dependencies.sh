#!/usr/bin/env bash
# Installs the Debian 12 packages hairmvs needs to build, test and run.
# Idempotent: apt is skipped entirely when every package is already installed.
set -euo pipefail

PACKAGES=(
  cmake g++ make pkg-config
  libeigen3-dev libceres-dev libgoogle-glog-dev libgflags-dev
  libopencv-dev
  ocl-icd-opencl-dev opencl-clhpp-headers opencl-c-headers pocl-opencl-icd clinfo
  colmap
  libmaxflow-dev
  libcgal-dev libgmp-dev libmpfr-dev
  libboost-program-options-dev libboost-filesystem-dev
  nlohmann-json3-dev libzip-dev zlib1g-dev libnanoflann-dev
  libopen3d-dev
  libgtest-dev libgmock-dev libbenchmark-dev
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "[install] all ${#PACKAGES[@]} Debian packages present; skipping apt"
  exit 0
fi

echo "[install] installing: ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
# Recommends included: the build was proven with them (Open3D was installed that way).
$SUDO apt-get install -y -qq "${missing[@]}"
