#!/usr/bin/env bash
# Install the Debian packages pik needs, and only those that are missing.
# Checks with dpkg-query first so that a warm machine never touches the network.
set -euo pipefail

packages=(
  cmake g++ make python3 python3-jinja2 python3-pytest
  libclang-14-dev llvm-14-dev llvm-14-tools clang-14
  libopenmpi-dev openmpi-bin libfmt-dev libgtest-dev
  python3-numpy python3-matplotlib python3-scipy
  libhdf5-dev
  pybind11-dev python3-pybind11 python3-dev python3-h5py libcli11-dev zlib1g-dev
  libfftw3-dev libfftw3-mpi-dev
  g++-aarch64-linux-gnu qemu-user
  gfortran
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "deps: all ${#packages[@]} Debian packages present"
  exit 0
fi

echo "deps: installing ${missing[*]}"
sudo=()
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
    sudo=(sudo -n)
  else
    echo "deps: error: missing packages (${missing[*]}) and not root (no passwordless sudo)." >&2
    echo "deps: run as root: apt-get install -y ${missing[*]}" >&2
    exit 1
  fi
fi

export DEBIAN_FRONTEND=noninteractive
if ! "${sudo[@]}" apt-get update -qq; then
  echo "deps: error: 'apt-get update' failed (no network or no Debian mirror reachable)." >&2
  exit 1
fi
if ! "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"; then
  echo "deps: error: 'apt-get install ${missing[*]}' failed; see the messages above." >&2
  exit 1
fi
echo "deps: installed ${#missing[@]} package(s)"
