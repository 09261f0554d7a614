#!/usr/bin/env bash
# Install what yade-mpm needs from Debian 12's packages (idempotent: apt runs only if something
# is missing). Run as root, or with sudo available.
set -euo pipefail
packages=(
  yade cmake make g++ libeigen3-dev libboost-python-dev libboost-serialization-dev
  libhdf5-dev googletest libgtest-dev python3-dev python3-pytest python3-numpy python3-h5py
  python3-matplotlib paraview
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} Debian packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}"
