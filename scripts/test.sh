#!/usr/bin/env bash
# Runs GI Lab's whole test suite. On a machine without a GPU it installs Mesa's software
# Vulkan driver (lavapipe), Xvfb, Chromium and GNU parallel when it may (root with apt-get), otherwise it says how.
set -euo pipefail
cd "$(dirname "$0")/.."

export WGPU_BACKEND="${WGPU_BACKEND:-vulkan}"
if [ -z "${XDG_RUNTIME_DIR:-}" ]; then
  export XDG_RUNTIME_DIR="$(mktemp -d /tmp/gi-lab-runtime.XXXXXX)"
  chmod 700 "$XDG_RUNTIME_DIR"
fi

need=()
# A Vulkan loader and an ICD (a real GPU driver or lavapipe).
if ! ls /usr/share/vulkan/icd.d/*.json /etc/vulkan/icd.d/*.json >/dev/null 2>&1 \
   || ! ldconfig -p 2>/dev/null | grep -q 'libvulkan.so.1'; then
  need+=(mesa-vulkan-drivers libvulkan1)
fi
command -v xvfb-run >/dev/null 2>&1 || need+=(xvfb xauth)
# `gi-lab study`'s tests: its page in a headless browser, its shards run by GNU parallel.
command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1 || need+=(chromium)
command -v parallel >/dev/null 2>&1 || need+=(parallel)

if [ ${#need[@]} -gt 0 ]; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "scripts/test.sh: installing ${need[*]}"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends "${need[@]}"
  else
    echo "scripts/test.sh: missing ${need[*]}." >&2
    echo "Install them with: sudo apt-get install -y --no-install-recommends ${need[*]}" >&2
    exit 1
  fi
fi

# A whole-suite run from scratch gains nothing from incremental compilation, whose caches
# would add about a gigabyte to target/ (CI's disk is small: docs/performance.md, "Build
# size"); set CARGO_INCREMENTAL=1 to keep them.
export CARGO_INCREMENTAL="${CARGO_INCREMENTAL:-0}"
cargo test --workspace "$@"
