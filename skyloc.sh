#!/usr/bin/env bash
# skyloc: install what is missing, build, test, run. See README.md.
#
#   ./skyloc.sh demo              build for this machine and run the demo on the simulated camera
#   ./skyloc.sh test              host + sanitizers + aarch64 + armhf (qemu-user) builds, every test
#   ./skyloc.sh build [KIND]      KIND: host (default), asan, tsan, aarch64, armhf, release
#   ./skyloc.sh bench [FILTER]    Release build, run the Google Benchmark programs
#   ./skyloc.sh run ARGS...       build host and run: skyloc ARGS...
#   ./skyloc.sh hil [KIND]        only the VM tests (label hil): host (amd64) or aarch64 (arm64)
#   ./skyloc.sh deps [KIND]       only install the Debian packages KIND needs
#   ./skyloc.sh format            clang-format every C++ file in place
#   ./skyloc.sh fuzz [--time S | --runs N] [TARGET...]
#                                 run the libFuzzer targets (default: all, 60 s each) on a
#                                 corpus kept in build/fuzz-corpus/ (docs/FUZZING.md)
#
# Builds go to build/<KIND>/, never into the source tree. Packages are installed with
# apt-get only when missing (root, or sudo when available).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
BUILD_ROOT="${SKYLOC_BUILD_ROOT:-$ROOT/build}"
JOBS="${SKYLOC_JOBS:-$(nproc)}"

say() { printf '\033[1mskyloc:\033[0m %s\n' "$*" >&2; }
die() {
  printf 'skyloc: error: %s\n' "$*" >&2
  exit 1
}

# ---------------------------------------------------------------------------------------
# Debian packages, by build kind.
HOST_PACKAGES=(build-essential cmake ninja-build pkg-config ccache googletest libgtest-dev
  libbenchmark-dev libeigen3-dev libtomlplusplus-dev libstb-dev libgpiod-dev gpiod
  libboost-math-dev
  libopencv-dev  # host-only evaluation tools: SIFT + k-means for the FAB-MAP baseline (docs/FABMAP.md)
  libcamera-dev
  clang-14 libclang-rt-14-dev)  # clang + libFuzzer: the fuzz targets (tests/fuzz)
# The HIL tests (tests/hil, CTest label hil): QEMU system emulators, what packs the VM's
# initramfs, the kernel headers the out-of-tree test drivers build against (the meta
# package follows Debian's current kernel ABI; tests/hil/setup.sh installs the exact one
# it needs when missing), Debian's tools the baseline checks run in the guest, and
# ShellCheck for the harness's scripts (lint.shellcheck_hil*).
HIL_PACKAGES=(qemu-system-x86 qemu-system-arm busybox-static kmod cpio bc xz-utils
  v4l-utils gpiod libcamera-tools libcamera-ipa shellcheck)
HIL_PACKAGES_amd64=(linux-headers-amd64)
CROSS_PACKAGES_aarch64=(crossbuild-essential-arm64 qemu-user-static)
CROSS_PACKAGES_armhf=(crossbuild-essential-armhf qemu-user-static)
# Optional target libraries from Debian multiarch. The archive's architectures are not
# always in step (a security update can reach amd64 before arm64), and then these are not
# co-installable; the build then leaves the driver out and says so at configure time.
CROSS_OPTIONAL_aarch64=(libgpiod-dev:arm64)
CROSS_OPTIONAL_armhf=(libgpiod-dev:armhf)

apt_updated=0
as_root() {
  if [ "$(id -u)" -eq 0 ]; then "$@"; elif command -v sudo >/dev/null; then sudo "$@"; else
    die "need root to install packages ($*): run as root or install sudo"
  fi
}
missing_packages() {
  local p
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || echo "$p"
  done
}
apt_update_once() {
  [ "$apt_updated" = 1 ] && return 0
  # An index that fails to download (a mirror mid-sync) is not fatal: apt keeps the old
  # one, and the install below says clearly if a package is really unavailable.
  as_root apt-get update -qq || say "apt-get update reported errors; continuing with the lists it has"
  apt_updated=1
}
install_packages() {
  local missing
  missing=$(missing_packages "$@")
  [ -z "$missing" ] && return 0
  apt_update_once
  say "installing: $(echo "$missing" | tr '\n' ' ')"
  # shellcheck disable=SC2086
  as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $missing \
    >"$BUILD_ROOT/apt.log" 2>&1 || {
    tail -20 "$BUILD_ROOT/apt.log" >&2
    die "apt-get install failed for: $(echo $missing | tr '\n' ' ') (log: $BUILD_ROOT/apt.log)"
  }
}
install_optional() {
  local p
  for p in $(missing_packages "$@"); do
    apt_update_once
    if ! as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "$p" \
      >>"$BUILD_ROOT/apt.log" 2>&1; then
      say "optional package $p is not installable right now; its driver is left out of this build"
    fi
  done
}
ensure_foreign_arch() {
  local arch=$1
  if ! dpkg --print-foreign-architectures | grep -qx "$arch"; then
    as_root dpkg --add-architecture "$arch"
    apt_updated=0
  fi
}

deps() {
  local kind=${1:-host}
  mkdir -p "$BUILD_ROOT"
  install_packages "${HOST_PACKAGES[@]}"
  case "$kind" in
    host | aarch64)
      install_packages "${HIL_PACKAGES[@]}"
      if [ "$(dpkg --print-architecture)" = amd64 ]; then install_packages "${HIL_PACKAGES_amd64[@]}"; fi
      ;;
  esac
  case "$kind" in
    host | asan | tsan | release) ;;
    aarch64)
      install_packages "${CROSS_PACKAGES_aarch64[@]}"
      ensure_foreign_arch arm64
      install_optional "${CROSS_OPTIONAL_aarch64[@]}"
      ;;
    armhf)
      install_packages "${CROSS_PACKAGES_armhf[@]}"
      ensure_foreign_arch armhf
      install_optional "${CROSS_OPTIONAL_armhf[@]}"
      ;;
    *) die "unknown build kind '$kind' (host, asan, tsan, release, aarch64, armhf)" ;;
  esac
}

# ---------------------------------------------------------------------------------------
configure_and_build() {
  local kind=${1:-host}
  local dir="$BUILD_ROOT/$kind"
  # The HIL VM cache is shared by the host and aarch64 builds (docs/HIL.md).
  local args=(-G Ninja -S "$ROOT" -B "$dir" -DSKYLOC_HIL_CACHE="$BUILD_ROOT/hil-cache")
  [ "${CI:-}" = "true" ] && args+=(-DSKYLOC_WERROR=ON)
  case "$kind" in
    host) args+=(-DCMAKE_BUILD_TYPE=RelWithDebInfo) ;;
    release) args+=(-DCMAKE_BUILD_TYPE=Release -DSKYLOC_BUILD_TESTS=OFF) ;;
    asan) args+=(-DCMAKE_BUILD_TYPE=Debug -DSKYLOC_SANITIZE=address -DSKYLOC_BUILD_BENCHMARKS=OFF) ;;
    tsan) args+=(-DCMAKE_BUILD_TYPE=Debug -DSKYLOC_SANITIZE=thread -DSKYLOC_BUILD_BENCHMARKS=OFF) ;;
    aarch64) args+=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_TOOLCHAIN_FILE="$ROOT/toolchains/aarch64-linux-gnu.cmake") ;;
    armhf) args+=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_TOOLCHAIN_FILE="$ROOT/toolchains/arm-linux-gnueabihf.cmake") ;;
    *) die "unknown build kind '$kind' (host, asan, tsan, release, aarch64, armhf)" ;;
  esac
  # A build folder configured by hand with another generator cannot be reused: start it afresh.
  if [ -f "$dir/CMakeCache.txt" ] && ! grep -q "^CMAKE_GENERATOR:INTERNAL=Ninja$" "$dir/CMakeCache.txt"; then
    say "$dir was configured with another generator; reconfiguring it from scratch"
    rm -rf "$dir"
  fi
  say "configuring $kind in $dir"
  cmake "${args[@]}" >"$BUILD_ROOT/configure-$kind.log" 2>&1 || {
    cat "$BUILD_ROOT/configure-$kind.log" >&2
    die "cmake configure failed for $kind"
  }
  grep -E "^-- skyloc:" "$BUILD_ROOT/configure-$kind.log" >&2 || true
  say "building $kind ($JOBS jobs)"
  cmake --build "$dir" -j "$JOBS" || die "build failed for $kind"
}

# Runs ctest in a build and records its pass/fail counts for the final summary line.
TOTAL_PASSED=0
TOTAL_FAILED=0
TOTAL_SKIPPED=0
FAILED_KINDS=()
run_ctest() {
  local kind=$1
  shift
  local dir="$BUILD_ROOT/$kind" log="$BUILD_ROOT/ctest-$kind.log" rc=0
  say "testing $kind: ctest $*"
  (cd "$dir" && ctest --output-on-failure -j "$JOBS" --timeout 900 "$@") 2>&1 | tee "$log" || rc=$?
  local line passed failed
  line=$(grep -E "tests passed, [0-9]+ tests failed out of [0-9]+" "$log" | tail -1 || true)
  if [ -z "$line" ]; then
    FAILED_KINDS+=("$kind(no result)")
    return 0
  fi
  failed=$(sed -E 's/.* ([0-9]+) tests failed out of ([0-9]+).*/\1/' <<<"$line")
  local total
  total=$(sed -E 's/.* tests failed out of ([0-9]+).*/\1/' <<<"$line")
  # CTest counts a skipped test (a VM test without QEMU, a real-driver test without a
  # device) as not failed; it is listed as "(Skipped)" and must not be reported as passed.
  local skipped
  skipped=$(grep -cE '^[[:space:]]+[0-9]+ - .* \(Skipped\)$' "$log" || true)
  passed=$((total - failed - skipped))
  TOTAL_PASSED=$((TOTAL_PASSED + passed))
  TOTAL_SKIPPED=$((TOTAL_SKIPPED + skipped))
  TOTAL_FAILED=$((TOTAL_FAILED + failed))
  if [ "$rc" -ne 0 ] || [ "$failed" -ne 0 ]; then FAILED_KINDS+=("$kind"); fi
}

cmd_test() {
  local start=$SECONDS
  deps host
  deps aarch64
  deps armhf
  configure_and_build host
  run_ctest host -LE hil
  # VM tests get one more try when they fail: libcamera 0.0.3 under QEMU TCG hung once in
  # 16 runs (docs/DRIVERS.md), and a hang is not a finding about skyloc. A real failure
  # fails both tries.
  run_ctest host -L hil --repeat until-pass:2
  configure_and_build asan
  # The sanitizer and aarch64 builds run every test but the VM ones (those boot a guest
  # with the host build's binaries) and the long soak runs (the host build runs those).
  run_ctest asan -LE "hil|slow"
  # ThreadSanitizer over what runs threads: the recorder's writer thread and its queue,
  # and eval's fork-join (the batch matcher and the descriptors). Not cli.firmware_modes:
  # it expects a recording without drops, and TSan slows the writer below the camera.
  # (The libcamera completion path runs in the VM only: docs/DRIVERS.md.)
  configure_and_build tsan
  run_ctest tsan -R "SpscQueue|FrameRecorder|ParallelFor|BlockedSeqSlamThreads|^cli[.]eval_(batch|streaming)$"
  configure_and_build aarch64
  # Every aarch64 test, the hil ones included: those boot an arm64 kernel in
  # qemu-system-aarch64 with the cross-built binaries (the rest run under qemu-user).
  # The slow soak runs are the host build's job.
  run_ctest aarch64 -LE "slow|hil"
  run_ctest aarch64 -L hil --repeat until-pass:2
  # 32-bit ARM (Raspberry Pi OS 32-bit, ARMv7 boards): what only a 32-bit target shows
  # (size_t and off_t of 32 bits, long double = double), under qemu-arm. No VM for it.
  configure_and_build armhf
  run_ctest armhf -LE "slow|hil"
  say "all test runs took $((SECONDS - start)) s"
  if [ ${#FAILED_KINDS[@]} -gt 0 ]; then
    echo "failing builds: ${FAILED_KINDS[*]}"
  fi
  # CI reads this closing line: "N passed, N failed" with ", N skipped" after it.
  echo "total: ${TOTAL_PASSED} passed, ${TOTAL_FAILED} failed, ${TOTAL_SKIPPED} skipped"
  [ ${#FAILED_KINDS[@]} -eq 0 ]
}

# Long fuzzing runs (the test suite runs each target for seconds only). Each target keeps
# its corpus in build/fuzz-corpus/TARGET between runs, seeded from the repository's
# example files; a crash stops the run with the input's path and a non-zero exit.
cmd_fuzz() {
  local limit=(-max_total_time=60) targets=()
  while [ $# -gt 0 ]; do
    case "$1" in
      --time)
        [[ "${2:-}" =~ ^[1-9][0-9]*$ ]] || die "fuzz --time needs seconds (a positive whole number), not '${2:-}'"
        limit=(-max_total_time="$2")
        shift 2
        ;;
      --runs)
        [[ "${2:-}" =~ ^[1-9][0-9]*$ ]] || die "fuzz --runs needs a count of executions, not '${2:-}'"
        limit=(-runs="$2")
        shift 2
        ;;
      -*) die "fuzz: unknown option '$1' (--time S, --runs N)" ;;
      *)
        targets+=("$1")
        shift
        ;;
    esac
  done
  deps host
  configure_and_build host
  local bin="$BUILD_ROOT/host/fuzz/tests/fuzz"
  [ -d "$bin" ] || die "no fuzz targets in $bin: the host build needs clang-14 and libclang-rt-14-dev (see $BUILD_ROOT/configure-host.log)"
  if [ ${#targets[@]} -eq 0 ]; then
    local t
    for t in "$bin"/*_fuzz; do targets+=("$(basename "$t" _fuzz)"); done
  fi
  local name exe corpus seeds log runs summary=()
  for name in "${targets[@]}"; do
    exe="$bin/${name}_fuzz"
    [ -x "$exe" ] || die "no fuzz target '$name' (targets: $(find "$bin" -maxdepth 1 -name '*_fuzz' -printf '%f ' | sed 's/_fuzz//g'))"
    corpus="$BUILD_ROOT/fuzz-corpus/$name"
    mkdir -p "$corpus"
    # Seeds: the repository's own examples of each input.
    seeds=()
    case "$name" in
      config) seeds=("$ROOT"/config/skyloc.toml "$ROOT"/tests/integration/small.toml) ;;
      camera_file) seeds=("$ROOT"/config/camera-*.toml) ;;
    esac
    [ -d "$ROOT/tests/fuzz/corpus/$name" ] && seeds+=("$ROOT/tests/fuzz/corpus/$name"/*)
    log="$BUILD_ROOT/fuzz-$name.log"
    say "fuzzing $name (${limit[*]}; corpus $corpus; log $log)"
    local seed_arg=()
    [ ${#seeds[@]} -gt 0 ] && seed_arg=(-seed_inputs="$(IFS=,; echo "${seeds[*]}")")
    (cd "$BUILD_ROOT" && "$exe" "${limit[@]}" -max_len=4096 -print_final_stats=1 \
      -artifact_prefix="$BUILD_ROOT/fuzz-crash-$name-" "${seed_arg[@]}" "$corpus") >"$log" 2>&1 || {
      tail -30 "$log" >&2
      die "fuzz target '$name' found a failure: the input is $BUILD_ROOT/fuzz-crash-$name-*; full log $log"
    }
    runs=$(sed -nE 's/^stat::number_of_executed_units: *([0-9]+).*/\1/p' "$log" | tail -1)
    summary+=("$name: ${runs:-?} executions, no failure, corpus $(find "$corpus" -type f | wc -l) inputs")
  done
  printf '%s\n' "${summary[@]}"
}

cmd_demo() {
  deps host
  configure_and_build host
  "$BUILD_ROOT/host/app/skyloc" demo "$@"
}

usage() { awk 'NR > 1 && !/^#/ { exit } NR > 1 { sub(/^# ?/, ""); print }' "$0"; }

main() {
  local cmd=${1:-}
  [ -n "$cmd" ] || {
    usage
    exit 2
  }
  shift
  mkdir -p "$BUILD_ROOT"
  case "$cmd" in
    demo) cmd_demo "$@" ;;
    test) cmd_test "$@" ;;
    fuzz) cmd_fuzz "$@" ;;
    build)
      deps "${1:-host}"
      configure_and_build "${1:-host}"
      ;;
    deps) deps "${1:-host}" ;;
    hil)
      local kind=${1:-host}
      case "$kind" in host | aarch64) ;; *) die "hil runs for host or aarch64, not '$kind'" ;; esac
      deps "$kind"
      configure_and_build "$kind"
      run_ctest "$kind" -L hil
      [ ${#FAILED_KINDS[@]} -eq 0 ] || die "hil tests failed (console logs: $BUILD_ROOT/$kind/hil-logs/)"
      ;;
    bench)
      deps host
      local dir="$BUILD_ROOT/bench"
      say "configuring Release benchmarks in $dir"
      cmake -G Ninja -S "$ROOT" -B "$dir" -DCMAKE_BUILD_TYPE=Release -DSKYLOC_BUILD_TESTS=OFF \
        >"$BUILD_ROOT/configure-bench.log" 2>&1 || die "cmake configure failed (see $BUILD_ROOT/configure-bench.log)"
      cmake --build "$dir" -j "$JOBS" || die "benchmark build failed"
      local b
      for b in "$dir"/tests/bench/*_bench; do
        say "running $(basename "$b")"
        "$b" ${1:+--benchmark_filter="$1"}
      done
      ;;
    run)
      deps host
      configure_and_build host >&2
      "$BUILD_ROOT/host/app/skyloc" "$@"
      ;;
    format)
      git -C "$ROOT" ls-files '*.cpp' '*.h' | (cd "$ROOT" && xargs clang-format -i)
      ;;
    -h | --help | help) usage ;;
    *)
      usage >&2
      die "unknown command '$cmd'"
      ;;
  esac
}

main "$@"
