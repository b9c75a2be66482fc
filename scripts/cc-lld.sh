#!/bin/sh
# The linker cargo calls on Linux x86-64 (.cargo/config.toml): the C compiler driver, as
# rustc's default, told to use LLVM's lld when it is installed. lld links a test binary several
# times faster than GNU ld (docs/runs/2026-12-04-build-and-test-time-issue-52s-fifth-step.md).
if command -v ld.lld >/dev/null 2>&1; then
  exec cc -fuse-ld=lld "$@"
fi
exec cc "$@"
