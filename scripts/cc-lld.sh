#!/bin/sh
# The linker cargo calls on Linux x86-64 (.cargo/config.toml): the C compiler driver, as
# rustc's default, told to use LLVM's lld when it is installed. lld links a test binary several
# times faster than GNU ld (docs/performance.md, "Build and test time, issue #52's fifth step").
if command -v ld.lld >/dev/null 2>&1; then
  exec cc -fuse-ld=lld "$@"
fi
exec cc "$@"
