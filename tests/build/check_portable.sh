#!/usr/bin/env bash
# The default build is portable: configured without ORGANSIM_NATIVE, no
# translation unit is compiled with -march=native, so the
# binary runs on every CPU of its architecture and the SIMD kernel picks the
# best target at run time (core/sim/cpu_kernel_simd.h). Reads the build
# folder's CMake cache and compile_commands.json.
set -euo pipefail
build=$1
cache=$build/CMakeCache.txt
commands=$build/compile_commands.json
native=$(sed -n 's/^ORGANSIM_NATIVE:BOOL=//p' "$cache")
if [ "$native" != OFF ]; then
  echo "FAIL: $cache has ORGANSIM_NATIVE=$native: the default must be OFF (configure without -DORGANSIM_NATIVE=ON)"
  exit 1
fi
[ -s "$commands" ] || { echo "FAIL: $commands missing or empty"; exit 1; }
units=$(grep -c '"file"' "$commands")
if grep -q -- '-march=native' "$commands"; then
  echo "FAIL: -march=native in $(grep -c -- '-march=native' "$commands") of $units compile commands"
  exit 1
fi
echo "portable: ORGANSIM_NATIVE=OFF, no -march=native in any of $units compile commands"
