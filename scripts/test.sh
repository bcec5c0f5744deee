#!/usr/bin/env bash
# Quick start, part 2: runs the whole test suite on Mesa's lavapipe, as CI does. The golden image and
# the tolerances are lavapipe's; set WGPU_ADAPTER_NAME to run the GPU tests elsewhere.
set -euo pipefail
cd "$(dirname "$0")/.."
MANYLIGHTS_NEED_LAVAPIPE=1 scripts/ensure-vulkan.sh
scripts/ensure-cxx.sh
# The viewer's test opens a window under Xvfb.
scripts/ensure-xvfb.sh
export WGPU_ADAPTER_NAME="${WGPU_ADAPTER_NAME:-llvmpipe}"
# Mesa's window-system probing warns without it; headless rendering does not need it.
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
cargo test --workspace "$@"
