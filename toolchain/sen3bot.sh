#!/usr/bin/env bash
# The two README commands.
#   toolchain/sen3bot.sh mission   install what building the simulator needs, build it
#                                  (sen3bot-sim only), run the simulated robot through the
#                                  thesis' three cases (report in build/report)
#   toolchain/sen3bot.sh test      install what is missing, build, run every test suite:
#                                  native (-Werror), ASan+UBSan, and aarch64 under qemu-user
#                                  and a bounded coverage-guided fuzzing run of every parser
# Environment: SEN3BOT_SKIP_SANITIZE=1 / SEN3BOT_SKIP_CROSS=1 / SEN3BOT_SKIP_FUZZ=1 leave those
# suites out; SEN3BOT_FUZZ_SECONDS is the libFuzzer time per parser (default 15);
# SEN3BOT_JOBS sets build parallelism (default: number of CPUs).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
jobs=${SEN3BOT_JOBS:-$(nproc)}

configure() {  # <build-dir> <cmake options...>
  local dir=$1
  shift
  cmake -S . -B "$dir" -G Ninja -DSEN3BOT_WERROR=ON "$@" >/dev/null
}

configure_and_build() {  # <build-dir> <cmake options...>: every target
  configure "$@"
  cmake --build "$1" -j "$jobs"
}

section() { printf '\n==== %s (%d s in) ====\n' "$*" "$((SECONDS - ${start:-SECONDS}))"; }

# A compiler cache outside the tree: a clean clone built again (CI) reuses the objects of the
# last run. Keyed on the preprocessed source and the flags, so it never serves a stale object.
use_ccache() {
  command -v ccache >/dev/null 2>&1 || return 0
  local dir=${CCACHE_DIR:-${XDG_CACHE_HOME:-${HOME:-/nonexistent}/.cache}/ccache}
  # A cache it cannot write would fail every compile: then build without one.
  mkdir -p "$dir" 2>/dev/null && [[ -w "$dir" ]] || return 0
  export CCACHE_DIR=$dir CCACHE_MAXSIZE=${CCACHE_MAXSIZE:-20G}
  # The tests compile against a precompiled header: ccache serves them only with these (its
  # documented settings for precompiled headers).
  export CCACHE_SLOPPINESS=${CCACHE_SLOPPINESS:-pch_defines,time_macros,include_file_mtime,include_file_ctime}
  export CMAKE_C_COMPILER_LAUNCHER=ccache CMAKE_CXX_COMPILER_LAUNCHER=ccache
}

case "${1:-}" in
  mission)
    start=$SECONDS
    section "installing missing packages"
    toolchain/bootstrap.sh --mission
    use_ccache
    section "building the simulator"
    # Only what the mission runs: the tests and benchmarks (and their packages) are the test
    # command's. The compile flags are the test command's, so either can follow the other and
    # reuse the other's objects.
    configure build -DSEN3BOT_TESTS=OFF -DSEN3BOT_BENCH=OFF
    cmake --build build -j "$jobs" --target sen3bot-sim
    section "running the simulated robot: the thesis' supervised-planning cases"
    exec build/firmware/sen3bot-sim sim --scenario thesis-sgp --report build/report
    ;;
  test)
    start=$SECONDS
    section "installing missing packages"
    if [[ "${SEN3BOT_SKIP_CROSS:-0}" == 1 ]]; then toolchain/bootstrap.sh; else toolchain/bootstrap.sh --cross; fi
    use_ccache
    section "native build and tests"
    configure_and_build build -DSEN3BOT_TESTS=ON -DSEN3BOT_BENCH=ON
    # Each external peer runs once: in the sanitized suite when there is one (tests/CMakeLists.txt).
    native_skip=()
    if [[ "${SEN3BOT_SKIP_SANITIZE:-0}" != 1 ]]; then native_skip=(-LE peer-sanitized); fi
    ctest --test-dir build --output-on-failure -j "$jobs" "${native_skip[@]}"
    # One clang tree for the sanitized suite and the fuzzers (with SEN3BOT_LIBFUZZER everything
    # carries libFuzzer's coverage counters): one build of the tree fewer than a tree for each.
    sanitize_args=(-DCMAKE_C_COMPILER=clang-16 -DCMAKE_CXX_COMPILER=clang++-16 -DSEN3BOT_SANITIZE=ON
                   -DSEN3BOT_BENCH=OFF)
    if [[ "${SEN3BOT_SKIP_FUZZ:-0}" != 1 ]]; then sanitize_args+=(-DSEN3BOT_LIBFUZZER=ON); fi
    export ASAN_SYMBOLIZER_PATH=/usr/lib/llvm-16/bin/llvm-symbolizer  # reports with file:line
    if [[ "${SEN3BOT_SKIP_SANITIZE:-0}" != 1 ]]; then
      section "AddressSanitizer + UndefinedBehaviorSanitizer build (clang) and tests"
      configure_and_build build-sanitize "${sanitize_args[@]}"
      # MRPT's client and the 30 s keep-alive run test peers and wall-clock time, not our memory
      # use; the native suite runs them. The fuzz corpora replay below, in the libFuzzer runs of
      # this same tree (each starts by running its whole corpus), unless fuzzing is skipped.
      sanitize_skip="slow|mrpt"
      if [[ "${SEN3BOT_SKIP_FUZZ:-0}" != 1 ]]; then sanitize_skip+="|fuzz"; fi
      ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
        LSAN_OPTIONS=suppressions="$root/toolchain/lsan.supp" \
        ctest --test-dir build-sanitize --output-on-failure -j "$jobs" -LE "$sanitize_skip"
    fi
    if [[ "${SEN3BOT_SKIP_FUZZ:-0}" != 1 ]]; then
      fuzz_s=${SEN3BOT_FUZZ_SECONDS:-15}
      section "coverage-guided fuzzing: libFuzzer + ASan + UBSan, ${fuzz_s} s per parser"
      configure build-sanitize "${sanitize_args[@]}"
      mapfile -t fuzz_targets < build-sanitize/fuzz_targets.txt
      targets=()
      for line in "${fuzz_targets[@]}"; do [[ -n "$line" ]] && targets+=("${line%% *}"); done
      # Built already unless the sanitized suite was skipped.
      cmake --build build-sanitize -j "$jobs" --target "${targets[@]}"
      # One libFuzzer process per core at a time (each is single-threaded); each reports when done.
      fuzz_one() {  # <binary name> <seed corpus> <work dir>
        local binary
        binary=$(find build-sanitize -type f -name "$1" | head -n 1)
        "$binary" -max_total_time="$fuzz_s" -rss_limit_mb=2048 -timeout=10 -print_final_stats=1 \
          -artifact_prefix="$3/" "$3" "$2" >"$3.log" 2>&1 || true
      }
      fuzz_report() {  # <binary name> <seed corpus> <work dir>: 1 when it found a failing input
        echo "fuzz: $1 (seeds: ${2#"$root"/})"
        grep -E '^(stat::number_of_executed_units|stat::peak_rss_mb|==|SUMMARY|.*(crash|leak|timeout)-)' "$3.log" || true
        if compgen -G "$3/crash-*" >/dev/null || compgen -G "$3/leak-*" >/dev/null || compgen -G "$3/timeout-*" >/dev/null; then
          echo "fuzz: $1 found a failing input (kept in $3)" >&2
          return 1
        fi
        rm -rf "$3" "$3.log"
      }
      pending=()
      fuzz_failed=0
      for line in "${fuzz_targets[@]}" ""; do
        if [[ -n "$line" ]]; then
          work=$(mktemp -d)  # new inputs go here; the checked-in corpus stays as it is
          fuzz_one "${line%% *}" "${line#* }" "$work" &
          pending+=("${line%% *}|${line#* }|$work|$!")
        fi
        if (( ${#pending[@]} >= jobs )) || [[ -z "$line" ]]; then
          for entry in "${pending[@]}"; do
            IFS='|' read -r name seeds work pid <<<"$entry"
            wait "$pid"
            fuzz_report "$name" "$seeds" "$work" || fuzz_failed=1
          done
          pending=()
        fi
      done
      (( fuzz_failed == 0 )) || exit 1
    fi
    if [[ "${SEN3BOT_SKIP_CROSS:-0}" != 1 ]]; then
      section "aarch64 cross build, tests under qemu-aarch64"
      qemu_closed_loop='^(ClosedLoop|ThesisCases|SgpLab|Kidnapped|SchedulerLoop)\.'
      qemu_closed_loop+='|^Firmware\.ASimulatedMinuteKeepsEveryRateExactly$|^Cli\.LockstepRunPrintsStatusAndStatistics$'
      qemu_closed_loop+='|^ZeroAllocation\.The(FirmwareWithTheFleetTask|CollaborativeMode)'
      qemu_closed_loop+='|^Mcl\.RecoversFromAKidnappingOnlyWithInjection$|^Dwa\.RecoversWhenBlockedAndCountsIt$'
      qemu_closed_loop+='|^DwaMovers\.(LetsACrossingBoxPass|TheBroadPhaseNeverChanges)'
      qemu_closed_loop+='|^SenseToAct\.|^Fleet\.(AnOrderDrives|BadMessages|ARobotCutOff)'
      qemu_closed_loop+='|^QrReaderRate\.WithinHalfAMetre|^Mapper\.ClosesTheLoop|^PoseGraph\.SolveTimeOf|^OnlineMapping\.'
      # Real-time pty runs and external peers are covered by the native and sanitized suites;
      # under an emulator ten times slower their timing says more about qemu than about the
      # firmware. So are the long closed-loop runs of the whole simulated robot (over 40 % of the
      # emulated time) and the longer of the QR reader's two rate sweeps: one closed-loop run, the
      # main job's mission, stays as the target's end-to-end run, beside the e-stop chain, the
      # whole table's allocation proof, the people detector and the blurred QR sweep.
      SEN3BOT_QEMU_EXCLUDE_LABELS=${SEN3BOT_QEMU_EXCLUDE_LABELS:-"slow|peer|mrpt|pty|lms200-pty"} \
      SEN3BOT_QEMU_EXCLUDE_TESTS=${SEN3BOT_QEMU_EXCLUDE_TESTS-$qemu_closed_loop} \
        toolchain/cross-test.sh aarch64
    fi
    section "all suites passed in $((SECONDS - start)) s"
    ;;
  *)
    echo "usage: $0 mission|test" >&2
    exit 2
    ;;
esac
