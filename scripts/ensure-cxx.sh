#!/usr/bin/env bash
# Makes sure a C++ compiler builds `manylights light-error`'s FLIP (the nv-flip crate compiles NVIDIA's
# reference implementation from source).
set -euo pipefail

if command -v c++ >/dev/null; then
  exit 0
fi
if ! command -v apt-get >/dev/null; then
  echo "error: building manylights needs a C++ compiler for FLIP (nv-flip); install one with your package manager (Debian: g++)" >&2
  exit 1
fi
source "$(dirname "$0")/apt-install.sh"
apt_install "a C++ compiler (for FLIP, nv-flip)" g++
