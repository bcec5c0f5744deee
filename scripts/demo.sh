#!/usr/bin/env bash
# Quick start, part 1: renders the built-in demo scene to demo.png (extra arguments go to `render`).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/ensure-vulkan.sh
scripts/ensure-cxx.sh
# Mesa's window-system probing warns without it; headless rendering does not need it.
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
cargo run --release -p manylights-cli -- render --scene demo -o demo.png "$@"
