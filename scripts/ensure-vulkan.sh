#!/usr/bin/env bash
# Makes sure a Vulkan loader and at least one Vulkan driver are installed. On a machine without a GPU
# driver this installs Mesa's software rasteriser (lavapipe, Debian/Ubuntu package mesa-vulkan-drivers),
# which runs everything manylights does, slowly.
#
# With MANYLIGHTS_NEED_LAVAPIPE=1 (the tests) lavapipe must be Mesa 24.1 or newer: older ones end a
# shader's loops after 65,535 iterations in all (and lack ray queries). On Debian 12, whose own Mesa is
# 22.3, it comes from bookworm-backports; elsewhere the distribution's must be new enough.
set -euo pipefail

# The oldest Mesa whose lavapipe the tests run on.
MIN_MESA=24.1

# File tests rather than ldconfig, which is not on a normal user's PATH on Debian.
have_loader() { compgen -G '/usr/lib/*/libvulkan.so.1' >/dev/null || compgen -G '/usr/lib*/libvulkan.so.1' >/dev/null; }
have_driver() {
  [ -n "${VK_DRIVER_FILES:-}${VK_ICD_FILENAMES:-}" ] && return 0
  compgen -G '/usr/share/vulkan/icd.d/*.json' >/dev/null || compgen -G '/etc/vulkan/icd.d/*.json' >/dev/null ||
    compgen -G '/usr/local/share/vulkan/icd.d/*.json' >/dev/null
}
have_lavapipe() { compgen -G '/usr/share/vulkan/icd.d/lvp_icd*.json' >/dev/null; }
# The installed Debian package's Mesa version (e.g. 25.0.7), or nothing.
mesa_version() { dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null | sed -E 's/^[0-9]+://; s/[-~+].*//' || true; }
# Whether version $1 is at least $2 (dotted numbers).
at_least() { [ "$(printf '%s\n%s\n' "$2" "$1" | sort -V | head -n1)" = "$2" ]; }
new_enough_lavapipe() {
  have_lavapipe || return 1
  local version
  version=$(mesa_version)
  # Without dpkg the version is unknown here; the tests' own checks then speak.
  [ -z "$version" ] && ! command -v dpkg-query >/dev/null && return 0
  [ -n "$version" ] && at_least "$version" "$MIN_MESA"
}

# Tests select lavapipe by name, so it is needed even beside a hardware driver when tests run.
want_lavapipe=${MANYLIGHTS_NEED_LAVAPIPE:-0}

if have_loader && have_driver && { [ "$want_lavapipe" = 0 ] || new_enough_lavapipe; }; then
  exit 0
fi

if ! command -v apt-get >/dev/null; then
  echo "error: no Vulkan driver found (or, for the tests, no lavapipe from Mesa $MIN_MESA or newer) and apt-get is" \
       "unavailable; install your GPU's Vulkan driver or Mesa's lavapipe (often packaged as mesa-vulkan-drivers or" \
       "vulkan-swrast)" >&2
  exit 1
fi
source "$(dirname "$0")/apt-install.sh"
if [ "$want_lavapipe" = 1 ] && grep -q '^VERSION_CODENAME=bookworm' /etc/os-release 2>/dev/null; then
  if ! grep -rqs 'bookworm-backports' /etc/apt/sources.list /etc/apt/sources.list.d/; then
    sudo=""
    [ "$(id -u)" != 0 ] && sudo="sudo"
    echo "deb http://deb.debian.org/debian bookworm-backports main" | $sudo tee /etc/apt/sources.list.d/bookworm-backports.list >/dev/null
  fi
  apt_install "the Vulkan loader and Mesa $MIN_MESA+'s software Vulkan driver (lavapipe) from bookworm-backports" \
    libvulkan1 -t bookworm-backports mesa-vulkan-drivers
else
  apt_install "the Vulkan loader and Mesa's software Vulkan driver (lavapipe)" libvulkan1 mesa-vulkan-drivers
fi
have_loader && have_driver || { echo "error: Vulkan still unavailable after installing mesa-vulkan-drivers" >&2; exit 1; }
if [ "$want_lavapipe" = 1 ] && ! new_enough_lavapipe; then
  echo "error: the tests need lavapipe from Mesa $MIN_MESA or newer, and this system has Mesa $(mesa_version);" \
       "install a newer mesa-vulkan-drivers (Debian 12: from bookworm-backports)" >&2
  exit 1
fi
