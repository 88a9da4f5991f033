#!/usr/bin/env bash
# Installs the Debian packages sysid needs, and only those that are missing, and
# the Python environment the Python package's tests build and run in
# (build/venv: nanobind, NumPy, pytest, python-control from the package index).
# Idempotent: a second run installs nothing. Run as root or with sudo available.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libsuitesparse-dev libspectra-dev libnlopt-cxx-dev libcli11-dev
  nlohmann-json3-dev libfast-float-dev googletest libgtest-dev libbenchmark-dev
  libmatio-dev  # MATLAB files out (sysid export --mat)
  gnuplot-nox
  python3  # scripts/check-layering.py
  python3-dev python3-venv  # the Python package (python/, pyproject.toml)
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
else
  echo "install-deps: installing ${missing[*]}"
  sudo_cmd=()
  if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# The ci preset builds the Python module with this interpreter (CMakePresets.json,
# Python_EXECUTABLE) and ctest runs the pytest tests with it. A venv of the
# python3 on PATH: pip may not install into a Debian system Python (PEP 668).
venv="$(cd "$(dirname "$0")/.." && pwd)/build/venv"
python_packages=(nanobind numpy pytest control)
if [ -x "$venv/bin/python" ] && "$venv/bin/python" -c "import nanobind, numpy, pytest, control" 2>/dev/null; then
  echo "install-deps: Python environment $venv present"
else
  echo "install-deps: making the Python environment $venv (${python_packages[*]})"
  # Only the Python module and its tests need it (the ci preset, README command 2):
  # without the package index the program still builds (README command 1), and the
  # ci preset's configure says what is missing.
  if ! { python3 -m venv "$venv" && "$venv/bin/pip" install --quiet --disable-pip-version-check "${python_packages[@]}"; }; then
    echo "install-deps: warning: could not make $venv (no package index?); the ci preset's Python module needs it" >&2
  fi
fi
