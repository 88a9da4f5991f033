#!/usr/bin/env bash
# Installs the Debian packages sysid needs, and only those that are missing.
# Idempotent: a second run installs nothing. Run as root or with sudo available.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libsuitesparse-dev libspectra-dev libnlopt-cxx-dev libcli11-dev
  nlohmann-json3-dev libfast-float-dev googletest libgtest-dev libbenchmark-dev
  gnuplot-nox
  python3  # scripts/check-layering.py
  clang libclang-rt-14-dev  # libFuzzer targets (tests/fuzz, scripts/fuzz-smoke.sh)
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
