#!/usr/bin/env bash
# Runs GI Lab's whole test suite: `cargo fmt --check` and clippy, then every test binary, as
# many at a time as there are cores. On a machine without a GPU it installs Mesa's software Vulkan
# driver (lavapipe), Xvfb, Chromium, GNU parallel and Slurm when it may (root with apt-get),
# otherwise it says how. `--quick` leaves out the slowest binaries (the inner loop); other
# arguments go to `cargo test --workspace` as they are.
set -euo pipefail
cd "$(dirname "$0")/.."

export WGPU_BACKEND="${WGPU_BACKEND:-vulkan}"
if [ -z "${XDG_RUNTIME_DIR:-}" ]; then
  export XDG_RUNTIME_DIR="$(mktemp -d /tmp/gi-lab-runtime.XXXXXX)"
  chmod 700 "$XDG_RUNTIME_DIR"
fi

need=()
# A Vulkan loader and an ICD (a real GPU driver or lavapipe).
if ! { ls /usr/share/vulkan/icd.d/*.json || ls /etc/vulkan/icd.d/*.json; } >/dev/null 2>&1 \
   || ! ldconfig -p 2>/dev/null | grep -q 'libvulkan.so.1'; then
  need+=(mesa-vulkan-drivers libvulkan1)
fi
command -v xvfb-run >/dev/null 2>&1 || need+=(xvfb xauth)
# `gi-lab study`'s tests: its page in a headless browser, its shards run by GNU parallel.
command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1 || need+=(chromium)
command -v parallel >/dev/null 2>&1 || need+=(parallel)
# `--emit-jobs slurm`'s tests submit to a real one-node Slurm (scripts/slurm-local.sh).
command -v slurmctld >/dev/null 2>&1 || need+=(slurmctld)
command -v slurmd >/dev/null 2>&1 || need+=(slurmd)
command -v sbatch >/dev/null 2>&1 || need+=(slurm-client)
command -v munged >/dev/null 2>&1 || need+=(munge)
# LLVM's linker: scripts/cc-lld.sh (cargo's linker here, .cargo/config.toml) links the ~60 test
# binaries with it, a minute faster than GNU ld on 2 cores.
command -v ld.lld >/dev/null 2>&1 || need+=(lld)
# The port kits' shaders (tests/port_kit.rs): SPIR-V checked by spirv-val, GLSL by glslang.
command -v spirv-val >/dev/null 2>&1 || need+=(spirv-tools)
command -v glslangValidator >/dev/null 2>&1 || need+=(glslang-tools)
# The Vulkan validation layer: tests/validation.rs runs every shipped preset under it.
layer=0
for d in /usr/share /usr/local/share /etc; do
  [ -e "$d/vulkan/explicit_layer.d/VkLayer_khronos_validation.json" ] && layer=1
done
[ "$layer" = 1 ] || need+=(vulkan-validationlayers)

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

# /dev/null must be the null device. On some container images it is a regular file: then
# every `2>/dev/null` of a build script's feature probe (a `#![feature]` test compile) writes
# its error text into it, and cargo's next probe of the compiler (`rustc - --print=…`, with
# /dev/null as its standard input) parses that text as Rust and fails: "failed to run `rustc`
# to learn about target-specific information … error[E0554]" — the second cargo command
# after a clean build always did. As root the device is made again; otherwise the file is
# emptied before each cargo command.
if [ ! -c /dev/null ]; then
  if [ "$(id -u)" = 0 ] && mknod -m 666 /dev/null.gi-lab c 1 3 2>/dev/null && mv -f /dev/null.gi-lab /dev/null; then
    echo "scripts/test.sh: /dev/null was a regular file; made it the null device again"
  else
    echo "scripts/test.sh: /dev/null is a regular file (not the null device); emptying it before each cargo command" >&2
  fi
fi
empty_null() { [ -c /dev/null ] || : >/dev/null; }

# Lavapipe compiles each shader variant with LLVM the first time a process uses it, and keeps
# it in Mesa's disk cache for the next: with a cold cache the sky's tests took 85 s instead of
# 16 (65 % of the time in LLVM). One writable cache for every test binary of the run, under
# target/, whatever $HOME is (docs/runs/2026-12-04-build-and-test-time-issue-52s-fifth-step.md).
export MESA_SHADER_CACHE_DIR="${MESA_SHADER_CACHE_DIR:-$PWD/target/mesa-shader-cache}"

# A whole-suite run from scratch gains nothing from incremental compilation, whose caches
# would add about a gigabyte to target/ (CI's disk is small: docs/performance.md, "Build
# size"); set CARGO_INCREMENTAL=1 to keep them.
export CARGO_INCREMENTAL="${CARGO_INCREMENTAL:-0}"

# Arguments other than --quick go to `cargo test --workspace` as they are (a test name, or
# `-- --nocapture`): the inner loop of one test.
quick=0
if [ "${1:-}" = "--quick" ]; then
  quick=1
  shift
fi
if [ $# -gt 0 ]; then
  empty_null
  exec cargo test --workspace "$@"
fi

# Nothing here reads standard input.
exec </dev/null

# Style first: a formatting slip fails in seconds, a lint in about two minutes, both before
# the suite's build.
cargo fmt --all --check
empty_null
cargo clippy --workspace --all-targets -- -D warnings
empty_null

# The suite. `cargo test` runs its test binaries one after another, each on as many threads
# as it has tests running; most binaries hold one to three long tests, so one of the two
# cores idled for much of the run (docs/runs/, the "Build and test time" runs). Here every
# binary is built first, then they run as many at a time as there are cores, the longest
# first (GNU parallel), each in its package's folder as `cargo test` runs it.
# `--quick` leaves out the slowest binaries (the window walk, the every-widget and quality
# tests): for the inner loop, never for CI.
slow_first="ui_walk ui cli quality preset_images knecht_quality ui_history gi_render study soak framing ui_no_wait"
quick_skips="ui_walk ui cli quality preset_images"
list="$(mktemp /tmp/gi-lab-tests.XXXXXX)"
trap 'rm -f "$list" "$list".*' EXIT
cargo test --workspace --no-run --message-format=json-render-diagnostics >"$list.json"
# One line per test binary: its package folder and its path.
grep '"reason":"compiler-artifact"' "$list.json" | grep -E '"profile":\{[^}]*"test":true' | grep '"executable":"/' |
  sed -E 's/.*"manifest_path":"([^"]*)\/Cargo.toml".*"executable":"([^"]*)".*/\1 \2/' >"$list.all"
rank() { # binary name (without its hash) → its place in slow_first, or 99
  local i=0 n
  for n in $slow_first; do
    [ "$n" = "$1" ] && { echo "$i"; return; }
    i=$((i + 1))
  done
  echo 99
}
while read -r dir exe; do
  name="$(basename "$exe")"
  name="${name%-*}"
  if [ "$quick" = 1 ] && [[ " $quick_skips " == *" $name "* ]]; then
    echo "scripts/test.sh --quick: leaving out $name" >&2
    continue
  fi
  # The validation layer slows every Vulkan call: only tests/validation.rs runs under it.
  validate=0
  [ "$name" = validation ] && validate=1
  echo "$(rank "$name") $dir $exe $validate"
done <"$list.all" | sort -n -s -k1,1 | cut -d' ' -f2- >"$list.run"
echo "scripts/test.sh: $(wc -l <"$list.run") test binaries, $(nproc) at a time"
status=0
rm -f target/tmp/port-kit-verify.md
parallel --will-cite --jobs "$(nproc)" --group --colsep ' ' --joblog "$list.log" \
  'cd {1} && WGPU_VALIDATION={3} {2}' :::: "$list.run" || status=$?
# The study tests' one-node Slurm stops itself when its test binary ends (a watchdog of
# scripts/slurm-local.sh): nothing of it may outlive the suite.
for _ in $(seq 60); do
  pgrep -f 'slurm-local.sh' >/dev/null 2>&1 || pgrep -f 'gi-lab-slurm-' >/dev/null 2>&1 || break
  sleep 0.5
done
if pgrep -af 'gi-lab-slurm-|slurm-local.sh' >&2; then
  echo "scripts/test.sh: the tests' Slurm is still running 30 s after the suite (above)" >&2
  status=1
fi
# No doc tests: the crates have none.
# Every binary's time, kept in target/test-times.txt (the slowest first) for whoever trims
# the suite next (docs/runs/, the "Build and test time" runs).
tail -n +2 "$list.log" | awk -F'\t' '{ n = $NF; sub(/^cd [^ ]* && /, "", n); sub(/^WGPU_VALIDATION=[0-9] /, "", n); sub(/.*\//, "", n); printf "%8.1f  %s  exit %s\n", $4, n, $7 }' |
  sort -rn >target/test-times.txt || true
echo "scripts/test.sh: the slowest binaries (s, sharing the cores; all in target/test-times.txt):"
head -12 target/test-times.txt
# The port kit host's verify tables (tests/tests/port_kit.rs, issue #54), for the CI log.
if [ -f target/tmp/port-kit-verify.md ]; then
  cat target/tmp/port-kit-verify.md
fi
if [ "$status" != 0 ]; then
  echo "scripts/test.sh: failed binaries:" >&2
  tail -n +2 "$list.log" | awk -F'\t' '$7 != 0 { print "  " $NF }' >&2
  exit 1
fi
