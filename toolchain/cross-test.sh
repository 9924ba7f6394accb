#!/usr/bin/env bash
# Cross-builds Sen3Bot for the Raspberry Pi and runs the test suite under qemu-user.
#
#   toolchain/cross-test.sh [aarch64|armhf] [--build-only] [--build-dir DIR] [--jobs N]
#                           [-- <extra cmake configure arguments>]
#
# 1. builds/refreshes the Debian sysroot (toolchain/sysroot.sh; quick when up to date),
# 2. configures <repo>/build-<arch> with toolchain/<triplet>.cmake, -DSEN3BOT_WERROR=ON and the
#    benchmarks off (they measure the host under emulation, which says nothing about the Pi),
# 3. builds with -j2 (override: --jobs N or SEN3BOT_JOBS),
# 4. runs ctest; every test executable runs through `qemu-<arch> -L <sysroot>` (the toolchain
#    file's CMAKE_CROSSCOMPILING_EMULATOR), GoogleTest discovery included. Exit status is
#    non-zero if the sysroot, the configure, the build or any test fails.
#
# Tests with a ctest label listed in SEN3BOT_QEMU_EXCLUDE_LABELS (a regex for ctest -LE) and
# tests whose names match SEN3BOT_QEMU_EXCLUDE_TESTS (a regex for ctest -E) are skipped; both
# are empty by default. docs/cross-build.md says which the test command excludes and why.
# SEN3BOT_SYSROOT overrides the sysroot directory (default <repo>/.sysroot-<arch>).
set -euo pipefail

readonly script_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
readonly repo_dir="$(cd "${script_dir}/.." && pwd)"

arch=aarch64
build_only=0
build_dir=""
jobs="${SEN3BOT_JOBS:-2}"
extra_cmake_args=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    aarch64|arm64) arch=aarch64 ;;
    armhf|arm) arch=armhf ;;
    --build-only) build_only=1 ;;
    --build-dir) build_dir="$2"; shift ;;
    --jobs|-j) jobs="$2"; shift ;;
    --) shift; extra_cmake_args=("$@"); break ;;
    -h|--help) sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "cross-test.sh: unknown argument '$1'" >&2; exit 2 ;;
  esac
  shift
done

case "${arch}" in
  aarch64) triplet=aarch64-linux-gnu; qemu=qemu-aarch64 ;;
  armhf) triplet=arm-linux-gnueabihf; qemu=qemu-arm ;;
esac
build_dir="${build_dir:-${repo_dir}/build-${arch}}"
sysroot="${SEN3BOT_SYSROOT:-${repo_dir}/.sysroot-${arch}}"

missing=()
for tool in cmake ctest "${triplet}-g++"; do
  command -v "${tool}" >/dev/null || missing+=("${tool}")
done
if [[ "${build_only}" == 0 ]] && ! command -v "${qemu}" >/dev/null \
   && ! command -v "${qemu}-static" >/dev/null; then
  missing+=("${qemu}")
fi
if [[ ${#missing[@]} -gt 0 ]]; then
  echo "cross-test.sh: missing ${missing[*]}; run: toolchain/bootstrap.sh --cross" >&2
  exit 1
fi
generator=()   # an existing build directory keeps its generator
if [[ ! -f "${build_dir}/CMakeCache.txt" ]] && command -v ninja >/dev/null; then generator=(-G Ninja); fi

phase_start=${SECONDS}
timings=()
phase_done() { timings+=("$1: $((SECONDS - phase_start)) s"); phase_start=${SECONDS}; }
print_timings() { echo "== cross-test ${arch} timings: ${timings[*]}"; }
trap print_timings EXIT

echo "== [${arch}] sysroot ${sysroot}"
SEN3BOT_SYSROOT="${sysroot}" "${script_dir}/sysroot.sh" "${arch}"
phase_done sysroot

echo "== [${arch}] configure ${build_dir}"
# An existing build dir configured without the toolchain (or for another arch) cannot be reused.
if [[ -f "${build_dir}/CMakeCache.txt" ]] \
   && ! grep -q "^CMAKE_TOOLCHAIN_FILE:.*${triplet}\.cmake$" "${build_dir}/CMakeCache.txt"; then
  echo "${build_dir} was configured with another toolchain; remove it first" >&2
  exit 1
fi
cmake -S "${repo_dir}" -B "${build_dir}" "${generator[@]}" \
  -DCMAKE_TOOLCHAIN_FILE="${script_dir}/${triplet}.cmake" \
  -DSEN3BOT_SYSROOT="${sysroot}" \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DSEN3BOT_WERROR=ON \
  -DSEN3BOT_BENCH=OFF \
  -DSEN3BOT_SANITIZE=OFF \
  -DSEN3BOT_LIBFUZZER=OFF \
  "${extra_cmake_args[@]}"
phase_done configure

echo "== [${arch}] build (-j${jobs})"
cmake --build "${build_dir}" --parallel "${jobs}"
phase_done build

if [[ "${build_only}" == 1 ]]; then
  exit 0
fi

echo "== [${arch}] ctest under ${qemu} -L ${sysroot}"
ctest_args=(--test-dir "${build_dir}" --output-on-failure --no-tests=error -j "${jobs}")
if [[ -n "${SEN3BOT_QEMU_EXCLUDE_LABELS:-}" ]]; then
  ctest_args+=(-LE "${SEN3BOT_QEMU_EXCLUDE_LABELS}")
  echo "   excluding labels: ${SEN3BOT_QEMU_EXCLUDE_LABELS}"
fi
if [[ -n "${SEN3BOT_QEMU_EXCLUDE_TESTS:-}" ]]; then
  ctest_args+=(-E "${SEN3BOT_QEMU_EXCLUDE_TESTS}")
  echo "   excluding tests: ${SEN3BOT_QEMU_EXCLUDE_TESTS}"
fi
status=0
ctest "${ctest_args[@]}" || status=$?
phase_done ctest
exit "${status}"
