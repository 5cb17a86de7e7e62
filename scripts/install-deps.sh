#!/usr/bin/env bash
# Installs the Debian (bookworm) packages needed to build and test purkinje,
# and only those that are missing. Safe to run again: with everything
# present it changes nothing and needs no network or root.
set -euo pipefail

packages=(
  cmake ninja-build g++ pkg-config ccache
  libglm-dev libceres-dev libeigen3-dev nlohmann-json3-dev libcli11-dev
  libembree-dev libopenimageio-dev openimageio-tools libopenexr-dev libtbb-dev
  libopencv-dev zlib1g-dev libpng-dev libjpeg-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  # The fuzzers (scripts/fuzz.sh): clang; its libFuzzer, ASan and UBSan
  # runtimes, which clang only recommends; llvm-symbolizer, for reports
  # that name functions and lines.
  clang libclang-rt-14-dev llvm
  gcovr python3
  # The Python package (python/, docs/python.md) and its tests; matplotlib
  # draws calibrate's and compare's figures (python/purkinje/figures.py).
  pybind11-dev python3-dev python3-numpy python3-pytest python3-pil python3-pandas python3-torch
  python3-matplotlib
  # The Slurm test (tests/slurm) starts a single-node cluster of its own.
  slurmctld slurmd slurm-client munge
)

if ! command -v dpkg-query >/dev/null 2>&1; then
  echo "install-deps: dpkg-query not found; this script expects Debian bookworm." >&2
  echo "install-deps: install these packages by hand: ${packages[*]}" >&2
  exit 1
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
if [ "$(id -u)" -eq 0 ]; then
  sudo=()
elif command -v sudo >/dev/null 2>&1; then
  sudo=(sudo)
else
  echo "install-deps: missing packages (${missing[*]}) and not root, and sudo is not available." >&2
  echo "install-deps: as root, run: apt-get install ${missing[*]}" >&2
  exit 1
fi

export DEBIAN_FRONTEND=noninteractive
if ! "${sudo[@]}" apt-get update; then
  echo "install-deps: apt-get update failed (network or sources.list?)" >&2
  exit 1
fi
if ! "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "${missing[@]}"; then
  echo "install-deps: apt-get install failed for: ${missing[*]}" >&2
  exit 1
fi
echo "install-deps: done"
