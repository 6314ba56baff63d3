#!/bin/sh
# Builds the gpu/ module on its own (CUDA + CMake, no TBB, no OpenVDB) on a
# machine with an NVIDIA device, runs the `gpu` tests and the GPU benchmark,
# and leaves the logs and the benchmark's CSV in OUT_DIR.
#
#   gpu/tests/run_device_checks.sh OUT_DIR [DEPS_DIR]
#
# DEPS_DIR (optional) holds what the machine may lack: `googletest/` (a copy
# of /usr/src/googletest) and `cli11/` (CLI11's include/ and
# share/cmake/CLI11/, for the benchmark). The CUDA architecture is the
# device's own (nvidia-smi), or 90 when it cannot be read.
set -u
out=${1:?usage: run_device_checks.sh OUT_DIR [DEPS_DIR]}
deps=${2:-}
[ -z "$deps" ] || deps=$(cd "$deps" && pwd)
here=$(cd "$(dirname "$0")/../.." && pwd)
mkdir -p "$out"
build=${BUILD_DIR:-/tmp/lodestone-gpu-build}
nvcc=$(command -v nvcc || echo /usr/local/cuda/bin/nvcc)
arch=$(nvidia-smi --query-gpu=compute_cap --format=csv,noheader 2>/dev/null | head -n1 | tr -d '. ')
[ -n "$arch" ] || arch=90
nvidia-smi > "$out/nvidia_smi.txt" 2>&1
set -- -DCMAKE_BUILD_TYPE=Release -DCMAKE_CUDA_COMPILER="$nvcc" -DCMAKE_CUDA_ARCHITECTURES="$arch"
if [ -n "$deps" ]; then
  [ -d "$deps/googletest" ] && set -- "$@" -DLODESTONE_GTEST_SOURCE_DIR="$deps/googletest"
  [ -d "$deps/cli11" ] && set -- "$@" -DCLI11_DIR="$deps/cli11/share/cmake/CLI11"
fi
echo "configure: $*"
cmake -S "$here/gpu" -B "$build" "$@" > "$out/configure.log" 2>&1 || { tail -n 40 "$out/configure.log"; exit 1; }
jobs=$(nproc 2>/dev/null || echo 4)
start=$(date +%s)
cmake --build "$build" -j"$jobs" > "$out/build.log" 2>&1 || { tail -n 60 "$out/build.log"; exit 1; }
echo "built in $(( $(date +%s) - start )) s (sm_$arch)"
ctest --test-dir "$build" -L gpu --output-on-failure -j1 > "$out/ctest.log" 2>&1
rc=$?
grep -E "tests passed|tests failed|Failed|SKIPPED|Skipped|\*\*\*" "$out/ctest.log" | head -n 40
if [ -x "$build/bench/lodestone-bench-gpu" ]; then
  "$build/bench/lodestone-bench-gpu" ${BENCH_ARGS:-} --csv "$out/bench_gpu.csv" > "$out/bench_gpu.log" 2>&1
  echo "benchmark exit $?"; cat "$out/bench_gpu.log"
else
  echo "benchmark not built (no CLI11)"
fi
exit $rc
