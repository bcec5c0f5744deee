#!/usr/bin/env bash
# Makes sure a Vulkan loader and at least one Vulkan driver are installed. On a machine without a GPU
# driver this installs Mesa's software rasteriser (lavapipe, Debian/Ubuntu package mesa-vulkan-drivers),
# which runs everything manylights does, slowly.
set -euo pipefail

# File tests rather than ldconfig, which is not on a normal user's PATH on Debian.
have_loader() { compgen -G '/usr/lib/*/libvulkan.so.1' >/dev/null || compgen -G '/usr/lib*/libvulkan.so.1' >/dev/null; }
have_driver() {
  [ -n "${VK_DRIVER_FILES:-}${VK_ICD_FILENAMES:-}" ] && return 0
  compgen -G '/usr/share/vulkan/icd.d/*.json' >/dev/null || compgen -G '/etc/vulkan/icd.d/*.json' >/dev/null ||
    compgen -G '/usr/local/share/vulkan/icd.d/*.json' >/dev/null
}
have_lavapipe() { compgen -G '/usr/share/vulkan/icd.d/lvp_icd*.json' >/dev/null; }

# Tests select lavapipe by name, so it is needed even beside a hardware driver when tests run.
want_lavapipe=${MANYLIGHTS_NEED_LAVAPIPE:-0}

if have_loader && have_driver && { [ "$want_lavapipe" = 0 ] || have_lavapipe; }; then
  exit 0
fi

if ! command -v apt-get >/dev/null; then
  echo "error: no Vulkan driver found and apt-get is unavailable; install your GPU's Vulkan driver" \
       "or Mesa's lavapipe (often packaged as mesa-vulkan-drivers or vulkan-swrast)" >&2
  exit 1
fi
source "$(dirname "$0")/apt-install.sh"
apt_install "the Vulkan loader and Mesa's software Vulkan driver (lavapipe)" libvulkan1 mesa-vulkan-drivers
have_loader && have_driver || { echo "error: Vulkan still unavailable after installing mesa-vulkan-drivers" >&2; exit 1; }
