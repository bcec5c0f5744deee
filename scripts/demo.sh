#!/usr/bin/env bash
# Quick start, part 1: renders the built-in demo scene to demo.png (extra arguments go to `render`).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/ensure-vulkan.sh
cargo run --release -p manylights-cli -- render --scene demo -o demo.png "$@"
