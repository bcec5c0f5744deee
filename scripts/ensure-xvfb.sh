#!/usr/bin/env bash
# Makes sure the viewer's test can open a window on a machine without a display: Xvfb (a virtual X
# server, run through xvfb-run) and the X11 client libraries winit loads at run time.
set -euo pipefail

have_libs() {
  for lib in libxkbcommon-x11.so.0 libXcursor.so.1 libX11-xcb.so.1 libXi.so.6 libXrandr.so.2; do
    compgen -G "/usr/lib/*/$lib" >/dev/null || compgen -G "/usr/lib*/$lib" >/dev/null || return 1
  done
}

if command -v xvfb-run >/dev/null && command -v xauth >/dev/null && have_libs; then
  exit 0
fi
if ! command -v apt-get >/dev/null; then
  echo "error: the viewer's test needs Xvfb (xvfb-run, xauth) and the X11 libraries winit loads; install them" \
       "with your package manager (Debian: xvfb xauth libxkbcommon-x11-0 libxcursor1 libx11-xcb1 libxi6 libxrandr2)" >&2
  exit 1
fi
source "$(dirname "$0")/apt-install.sh"
apt_install "Xvfb and the X11 libraries the viewer loads" xvfb xauth libxkbcommon-x11-0 libxcursor1 libx11-xcb1 libxi6 libxrandr2
