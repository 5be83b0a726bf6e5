#!/usr/bin/env bash
# skyloc: install what is missing, build, test, run. See README.md.
#
#   ./skyloc.sh demo              build for this machine and run the demo on the simulated camera
#   ./skyloc.sh test              host + sanitizers + aarch64 + armhf (qemu-user) builds, every test
#   ./skyloc.sh build [KIND]      KIND: host (default), asan, tsan, aarch64, armhf, release
#   ./skyloc.sh bench [FILTER]    Release build, run the Google Benchmark programs
#   ./skyloc.sh run ARGS...       build host and run: skyloc ARGS...
#   ./skyloc.sh hil [KIND]        only the VM tests (label hil): host (amd64) or aarch64 (arm64)
#   ./skyloc.sh package [KIND]    Release build, build/skyloc_<version>_<arch>.deb; KIND: host, aarch64, armhf
#   ./skyloc.sh deps [KIND]       only install the Debian packages KIND needs (demo: the demo's)
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
# Debian packages, by purpose; deps() below picks them per build kind.
# The host build of the skyloc executable, all ./skyloc.sh demo installs: compilers, build
# tools and what the firmware includes and links. The drivers' libraries and Cyclone DDS
# ([output] dds: cyclonedds-dev, and cyclonedds-tools for its IDL compiler idlc) are in it
# because what a build contains is a compile definition of every file (SKYLOC_WITH_*): a
# demo built without them would make the test's build compile everything again.
BUILD_PACKAGES=(build-essential cmake ninja-build pkg-config ccache libeigen3-dev
  libtomlplusplus-dev libstb-dev libgpiod-dev libcamera-dev cyclonedds-dev cyclonedds-tools)
# The tests and benchmarks: GoogleTest and GoogleMock (Debian's builds; the ARM ones from
# the sysroot), Google Benchmark, and Boost.Math, the spherical-harmonics tests' reference.
TEST_PACKAGES=(libgtest-dev libgmock-dev libbenchmark-dev libboost-math-dev)
# The lab's tools (app/tools): SIFT + k-means for the FAB-MAP baseline (docs/FABMAP.md).
TOOLS_PACKAGES=(libopencv-dev)
# clang + libFuzzer: the fuzz targets (tests/fuzz).
FUZZ_PACKAGES=(clang-14 libclang-rt-14-dev)
# ./skyloc.sh package and its tests (tests/package): lint, install in a Debian root.
PACKAGE_PACKAGES=(lintian mmdebstrap)
# The HIL tests (tests/hil, CTest label hil): QEMU system emulators, what packs the VM's
# initramfs, the kernel headers the out-of-tree test drivers build against (the meta
# package follows Debian's current kernel ABI; tests/hil/setup.sh installs the exact one
# it needs when missing), Debian's tools the baseline checks run in the guest, and
# ShellCheck for the harness's scripts (lint.shellcheck_hil*).
HIL_PACKAGES=(qemu-system-x86 qemu-system-arm busybox-static kmod cpio bc xz-utils
  v4l-utils gpiod libcamera-tools libcamera-ipa shellcheck)
HIL_PACKAGES_amd64=(linux-headers-amd64)
# The ARM builds: Debian's cross compilers, qemu-user for their tests, and mmdebstrap,
# which makes each build's target sysroot (ensure_sysroot below).
CROSS_PACKAGES_aarch64=(crossbuild-essential-arm64 qemu-user-static mmdebstrap)
CROSS_PACKAGES_armhf=(crossbuild-essential-armhf qemu-user-static mmdebstrap)
# What the ARM builds include and link: toolchains/sysroot-packages.txt.
SYSROOT_PACKAGES_FILE="$ROOT/toolchains/sysroot-packages.txt"
# Bump when ensure_sysroot changes what it makes, so every cached sysroot is made again.
SYSROOT_FORMAT=1

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
# ---------------------------------------------------------------------------------------
# Target sysroots: a minimal Debian root of the target architecture holding the -dev
# packages of toolchains/sysroot-packages.txt and their dependencies, extracted (not
# configured: nothing of the target runs) by mmdebstrap from the archive this machine's apt
# uses. Cached in build/sysroot-<arch>/; made again only when the package list, the suite
# or SYSROOT_FORMAT changes (the hash in skyloc-sysroot/stamp).

ensure_sysroot() {
  local arch=$1 # Debian's name: arm64, armhf
  local dir="$BUILD_ROOT/sysroot-$arch" suite packages want
  suite=$("$ROOT/toolchains/debian-sources.sh" --suite) || die "the $arch sysroot is made from this machine's Debian suite"
  packages=$(sed -e 's/#.*//' "$SYSROOT_PACKAGES_FILE" | xargs)
  [ -n "$packages" ] || die "$SYSROOT_PACKAGES_FILE lists no packages"
  want=$(printf '%s\n' "format $SYSROOT_FORMAT" "$arch" "$suite" "$packages" | sha256sum | cut -d' ' -f1)
  if [ "$(cat "$dir/skyloc-sysroot/stamp" 2>/dev/null)" = "$want" ]; then
    if [ -f "$dir/skyloc-sysroot/suites-left-out" ]; then
      say "WARNING: $dir was made without $(cat "$dir/skyloc-sysroot/suites-left-out") (its $arch index could not be downloaded then); delete it to make it again"
    fi
    return 0
  fi
  command -v mmdebstrap >/dev/null || die "mmdebstrap is missing: it makes the $arch sysroot (apt-get install mmdebstrap; ./skyloc.sh deps does)"
  local sources=()
  mapfile -t sources < <("$ROOT/toolchains/debian-sources.sh")
  [ ${#sources[@]} -gt 0 ] || die "apt knows no source for Debian '$suite' (apt-get indextargets): the $arch sysroot is made from the archive this machine's apt uses"
  say "making the $arch sysroot in $dir with mmdebstrap: $packages"
  local log="$BUILD_ROOT/sysroot-$arch.log" start=$SECONDS attempt skipped=()
  # The extract hook runs while the downloaded packages are still in the target's apt
  # cache: it keeps their versions (for reports) and their shlibs files, which
  # dpkg-shlibdeps reads to compute the .deb's Depends (an extracted root has no dpkg
  # database).
  for attempt in 1 2; do
    rm -rf "$dir" "$dir.new"
    # shellcheck disable=SC2016 # the hooks' $1 is mmdebstrap's, expanded by its shell
    if as_root mmdebstrap --variant=extract --architectures="$arch" --include="${packages// /,}" \
      --extract-hook='mkdir -p "$1/skyloc-sysroot"' \
      --extract-hook='for d in "$1"/var/cache/apt/archives/*.deb; do dpkg-deb -f "$d" Package Version | paste -sd" "; done | sort >"$1/skyloc-sysroot/packages"' \
      --extract-hook='for d in "$1"/var/cache/apt/archives/*.deb; do dpkg-deb --ctrl-tarfile "$d" | tar -xO --wildcards "*shlibs" 2>/dev/null || true; done | grep -v "^udeb:" >"$1/skyloc-sysroot/shlibs"' \
      "$suite" "$dir.new" "${sources[@]}" >"$log" 2>&1; then
      break
    fi
    grep -E "^(E|Err):" "$log" | tail -6 >&2
    rm -rf "$dir.new"
    # An archive whose -updates or -security index for this architecture does not match
    # its Release file (a mirror mid-sync, or a frozen mirror that stayed so: seen here for
    # bookworm-security armhf) fails apt-get update. The sysroot is then made once more
    # without that suite, loudly, and says so at every build until it is made again.
    local failed
    failed=$(grep -oE "Failed to fetch [^ ]*/dists/[^/]+/" "$log" | sed -E 's|.*/dists/([^/]+)/|\1|' | sort -u | xargs)
    if [ "$attempt" = 1 ] && [ -n "$failed" ] && ! grep -qx "$suite" <<<"${failed// /$'\n'}"; then
      say "WARNING: the archive's $arch index of $failed cannot be downloaded (above); making the $arch sysroot without $failed"
      skipped=("$failed")
      local kept=() line
      for line in "${sources[@]}"; do
        [[ " $failed " == *" $(awk '{print $3}' <<<"$line") "* ]] || kept+=("$line")
      done
      sources=("${kept[@]}")
      continue
    fi
    die "mmdebstrap could not make the $arch sysroot (log: $log). Is the Debian archive reachable (${sources[*]}), and does it carry $arch?"
  done
  # Absolute symbolic links (libc6-dev's libm.so -> /lib/...) would point into the build
  # machine's root: make them relative, inside the sysroot. Device nodes and /tmp are not
  # wanted: qemu-user -L would show the sysroot's /dev and /tmp to the tests.
  local link
  while IFS= read -r -d '' link; do
    ln -sfn --relative "$dir.new$(readlink "$link")" "$link"
  done < <(find "$dir.new" -type l -lname '/*' -print0)
  rm -rf "$dir.new/dev" "$dir.new/tmp" "$dir.new/var/cache" "$dir.new/var/log"
  echo "$want" >"$dir.new/skyloc-sysroot/stamp"
  if [ ${#skipped[@]} -gt 0 ]; then echo "${skipped[*]}" >"$dir.new/skyloc-sysroot/suites-left-out"; fi
  mv "$dir.new" "$dir"
  say "$arch sysroot ready in $((SECONDS - start)) s ($(du -sh "$dir" | cut -f1), $(wc -l <"$dir/skyloc-sysroot/packages") packages)"
}

# ./skyloc.sh test installs first what the host build, its tests and its VM tests use
# (deps host). The ARM builds' cross compilers, qemu-user and sysroots (about 40 s of
# downloading and unpacking on the 2-core machine) are installed by cross_deps in the
# background, beside the host build. The VM job waits for it before its first VM (see
# vm_tests), the aarch64 build, minutes later, before compiling.
CROSS_READY="$BUILD_ROOT/cross.ready"
CROSS_FAILED="$BUILD_ROOT/cross.failed"
cross_deps() {
  local start=$SECONDS
  if (deps aarch64 && deps armhf); then
    note_phase "ARM packages, sysroots" "$start"
    touch "$CROSS_READY"
  else
    touch "$CROSS_FAILED"
    return 1
  fi
}
# Waits (in any job) until cross_deps has ended; fails when it failed.
await_cross_deps() {
  while [ ! -e "$CROSS_READY" ] && [ ! -e "$CROSS_FAILED" ]; do sleep 1; done
  [ -e "$CROSS_READY" ]
}

# deps demo: the skyloc executable only. Every build kind: all the host build's packages
# (its tests, tools, fuzz targets and package test), and for host and aarch64 the VM
# tests', for the ARM kinds the cross compilers and the sysroot.
deps() {
  local kind=${1:-host}
  mkdir -p "$BUILD_ROOT"
  install_packages "${BUILD_PACKAGES[@]}"
  [ "$kind" = demo ] && return 0
  install_packages "${TEST_PACKAGES[@]}" "${TOOLS_PACKAGES[@]}" "${FUZZ_PACKAGES[@]}" "${PACKAGE_PACKAGES[@]}"
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
      ensure_sysroot arm64
      ;;
    armhf)
      install_packages "${CROSS_PACKAGES_armhf[@]}"
      ensure_sysroot armhf
      ;;
    *) die "unknown build kind '$kind' (demo, host, asan, tsan, release, aarch64, armhf)" ;;
  esac
}

# ---------------------------------------------------------------------------------------
# configure_and_build KIND [TARGET...]: configure build/KIND and build the targets (all by
# default). KIND demo is the host build's folder, configured to build what the packages
# of deps demo allow: it shares build/host with the test run, so nothing is built twice.
configure_and_build() {
  local kind=${1:-host}
  shift || true
  local dir="$BUILD_ROOT/$kind"
  [ "$kind" = demo ] && dir="$BUILD_ROOT/host"
  # The HIL VM cache is shared by the host and aarch64 builds (docs/HIL.md).
  local args=(-G Ninja -S "$ROOT" -B "$dir" -DSKYLOC_HIL_CACHE="$BUILD_ROOT/hil-cache")
  [ "${CI:-}" = "true" ] && args+=(-DSKYLOC_WERROR=ON)
  # The builds that exist to run the demo and the tests (host, the sanitizers): line
  # tables (-g1) are all their reports and backtraces use, and full debug information (-g)
  # made compiling about a quarter slower (measured: 18 s of CPU against 23 s on the
  # heaviest test file, 7.3 s against 10.4 s on app/tools/experiment.cpp). To step through
  # locals in a debugger, configure a Debug build of your own. The ARM builds, whose
  # programs only run under qemu-user here (which prints no backtrace, and has no
  # sanitizer to symbolise), have none: -g1 made their compiling a fifth slower (measured
  # 2026-11-28 on the dsp tests' heaviest unit for aarch64: 19.2 s of CPU against 14.9 s).
  # Their optimisation stays -O2, as the host's, and as the numbers in the tests expect.
  local optimised_with_lines="-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG"
  local optimised_arm=(-DCMAKE_CXX_FLAGS_RELEASE="-O2 -DNDEBUG" -DCMAKE_C_FLAGS_RELEASE="-O2 -DNDEBUG")
  # The builds whose whole suite ./skyloc.sh test runs (ASan, under qemu-user) run each
  # GoogleTest program as 4 CTest tests rather than one process a case: a process start
  # costs 0.1-0.3 s of CPU there (cmake/SkylocModule.cmake). The host build keeps one test
  # a case (its run picks cases by label), as does TSan (by name).
  case "$kind" in
    asan | aarch64 | armhf) args+=(-DSKYLOC_GTEST_SHARDS=4) ;;
    *) args+=(-DSKYLOC_GTEST_SHARDS=0) ;;
  esac
  case "$kind" in
    # Tests and tools ON, not the default left in the cache by a demo: missing libraries
    # fail the configure instead of leaving tests out.
    host) args+=(-DCMAKE_BUILD_TYPE=RelWithDebInfo "$optimised_with_lines" -DSKYLOC_BUILD_TESTS=ON -DSKYLOC_TOOLS=ON) ;;
    demo) args+=(-DCMAKE_BUILD_TYPE=RelWithDebInfo "$optimised_with_lines" -DSKYLOC_BUILD_TESTS=AUTO -DSKYLOC_TOOLS=AUTO) ;;
    release) args+=(-DCMAKE_BUILD_TYPE=Release -DSKYLOC_BUILD_TESTS=OFF) ;;
    # What goes into the .deb: Release, the firmware only, every driver required.
    package-*)
      args+=(-DCMAKE_BUILD_TYPE=Release -DSKYLOC_BUILD_TESTS=OFF -DSKYLOC_BUILD_BENCHMARKS=OFF
        -DSKYLOC_TOOLS=OFF -DSKYLOC_WITH_V4L2=ON -DSKYLOC_WITH_GPIOD=ON -DSKYLOC_WITH_LIBCAMERA=ON)
      case "$kind" in
        package-host) ;;
        package-aarch64) args+=(-DCMAKE_TOOLCHAIN_FILE="$ROOT/toolchains/aarch64-linux-gnu.cmake"
          -DSKYLOC_SYSROOT="$BUILD_ROOT/sysroot-arm64") ;;
        package-armhf) args+=(-DCMAKE_TOOLCHAIN_FILE="$ROOT/toolchains/arm-linux-gnueabihf.cmake"
          -DSKYLOC_SYSROOT="$BUILD_ROOT/sysroot-armhf") ;;
        *) die "unknown package kind '${kind#package-}' (host, aarch64, armhf)" ;;
      esac
      ;;
    asan) args+=(-DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG=-g1 -DSKYLOC_SANITIZE=address
      -DSKYLOC_BUILD_BENCHMARKS=OFF) ;;
    tsan) args+=(-DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG=-g1 -DSKYLOC_SANITIZE=thread
      -DSKYLOC_BUILD_BENCHMARKS=OFF) ;;
    # No benchmarks in the ARM builds either (nothing runs them there; stage_cost counts
    # their instructions).
    aarch64) args+=(-DCMAKE_BUILD_TYPE=Release "${optimised_arm[@]}"
      -DSKYLOC_BUILD_BENCHMARKS=OFF -DCMAKE_TOOLCHAIN_FILE="$ROOT/toolchains/aarch64-linux-gnu.cmake" -DSKYLOC_SYSROOT="$BUILD_ROOT/sysroot-arm64") ;;
    armhf) args+=(-DCMAKE_BUILD_TYPE=Release "${optimised_arm[@]}"
      -DSKYLOC_BUILD_BENCHMARKS=OFF -DCMAKE_TOOLCHAIN_FILE="$ROOT/toolchains/arm-linux-gnueabihf.cmake" -DSKYLOC_SYSROOT="$BUILD_ROOT/sysroot-armhf") ;;
    *) die "unknown build kind '$kind' (demo, host, asan, tsan, release, aarch64, armhf)" ;;
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
  local targets=()
  [ $# -gt 0 ] && targets=(--target "$@")
  say "building $kind${targets:+ ($*)} ($JOBS jobs)"
  cmake --build "$dir" -j "$JOBS" "${targets[@]}" || die "build failed for $kind"
}

# Runs ctest in DIR (a build folder, or one of its test folders: a ctest there runs only
# that folder's tests and keeps its own Testing/ records, so two runs in one build do not
# share them) and writes its counts to $RESULTS_DIR/NAME, which summarise_results adds
# up; a run in the background reports the same way.
#   run_ctest NAME DIR CTEST-ARGS...
RESULTS_DIR="$BUILD_ROOT/test-results"
NICE=()
run_ctest() {
  local name=$1 dir=$2
  shift 2
  local log="$BUILD_ROOT/ctest-$name.log" rc=0
  mkdir -p "$RESULTS_DIR"
  say "testing $name: ctest $*"
  rm -rf "$dir/test-cases"
  (cd "$dir" && "${NICE[@]}" ctest --output-on-failure -j "$JOBS" --timeout 900 "$@") 2>&1 | tee "$log" || rc=$?
  local line
  line=$(grep -E "tests passed, [0-9]+ tests failed out of [0-9]+" "$log" | tail -1 || true)
  if [ -z "$line" ]; then
    echo "0 0 0 no-result" >"$RESULTS_DIR/$name"
    return 0
  fi
  local failed total skipped verdict=ok
  failed=$(sed -E 's/.* ([0-9]+) tests failed out of ([0-9]+).*/\1/' <<<"$line")
  total=$(sed -E 's/.* tests failed out of ([0-9]+).*/\1/' <<<"$line")
  # CTest counts a skipped test (a VM test without QEMU, a real-driver test without a
  # device) as not failed; it is listed as "(Skipped)" and must not be reported as passed.
  skipped=$(grep -cE '^[[:space:]]+[0-9]+ - .* \(Skipped\)$' "$log" || true)
  if [ "$rc" -ne 0 ] || [ "$failed" -ne 0 ]; then verdict=failed; fi
  local passed=$((total - failed - skipped)) counts
  counts=$(count_shard_cases "$dir" "$log")
  local shards shards_failed cases_passed cases_failed cases_skipped
  read -r shards shards_failed cases_passed cases_failed cases_skipped <<<"$counts"
  echo "$((passed - (shards - shards_failed) + cases_passed)) $((failed - shards_failed + cases_failed))" \
    "$((skipped + cases_skipped)) $verdict" >"$RESULTS_DIR/$name"
}

# A GoogleTest program run as shards (SKYLOC_GTEST_SHARDS, cmake/SkylocModule.cmake) is one
# CTest test a shard; its cases are counted from the XML each shard writes to
# DIR/test-cases/NAME.xml. A failed shard counts its failed cases, or one failure when it
# names none (it crashed, timed out, or the leak check failed it after its cases passed).
#   count_shard_cases DIR LOG -> "shards shards-failed cases-passed cases-failed cases-skipped"
count_shard_cases() {
  local dir=$1 log=$2 shards shards_failed=0 passed=0 failed=0 skipped=0 xml tests failures skips test
  shards=$(grep -cE '^ *[0-9]+/[0-9]+ Test +#[0-9]+: [^ ]+[.]shard[0-9]+ ' "$log" || true)
  for xml in "$dir"/test-cases/*.xml; do
    [ -f "$xml" ] || continue
    read -r tests failures < <(sed -nE 's/.*<testsuites tests="([0-9]+)" failures="([0-9]+)".*/\1 \2/p' "$xml")
    skips=$(grep -c 'result="skipped"' "$xml" || true)
    passed=$((passed + ${tests:-0} - ${failures:-0} - skips))
    failed=$((failed + ${failures:-0}))
    skipped=$((skipped + skips))
  done
  while read -r test; do
    [ -n "$test" ] || continue
    shards_failed=$((shards_failed + 1))
    xml="$dir/test-cases/$test.xml"
    if [ ! -f "$xml" ] || grep -qE '<testsuites tests="[0-9]+" failures="0"' "$xml"; then
      failed=$((failed + 1))
    fi
  done < <(sed -n '/^The following tests FAILED:/,/^$/p' "$log" |
    sed -nE 's/^[[:space:]]+[0-9]+ - ([^ ]+[.]shard[0-9]+) .*/\1/p')
  echo "$shards $shards_failed $passed $failed $skipped"
}

# The runs that did not pass (their names), from the counts run_ctest wrote.
failed_runs() {
  local f passed failed skipped verdict
  for f in "$RESULTS_DIR"/*; do
    [ "$(basename "$f")" = phases ] && continue
    read -r passed failed skipped verdict <"$f"
    [ "$verdict" = ok ] || printf '%s ' "$(basename "$f")($verdict)"
  done
}

# The failed tests of every run and the first lines of what each printed, from its ctest
# log: CI keeps only the end of the output, and a failure far above must be told there.
report_failed_tests() {
  local f name log passed failed skipped verdict
  for f in "$RESULTS_DIR"/*; do
    name=$(basename "$f")
    [ "$name" = phases ] && continue
    read -r passed failed skipped verdict <"$f"
    log="$BUILD_ROOT/ctest-$name.log"
    if [ "$verdict" = ok ] || ! grep -qs '^The following tests FAILED:' "$log"; then continue; fi
    echo "failed in $name:"
    sed -n '/^The following tests FAILED:/,/^$/p' "$log" | sed '1d;/^$/d'
    grep -E -A 30 '^ *[0-9]+/[0-9]+ Test +#[0-9]+: .*[*][*][*](Failed|Timeout|Exception)' "$log" |
      head -120 | sed 's/^/    | /'
    # A shard's output begins with the cases that passed: its failed cases, and where.
    grep -E -A 6 '(: Failure$|^\[  FAILED  \] [^ ]+ \()' "$log" | head -80 | sed 's/^/    > /'
  done
}

# phase NAME COMMAND...: runs COMMAND and notes its wall time for the closing table.
phase() {
  local name=$1 start=$SECONDS
  shift
  "$@"
  note_phase "$name" "$start"
}
note_phase() { printf '%-22s %4d s\n' "$1" $((SECONDS - $2)) >>"$RESULTS_DIR/phases"; }

# The VM tests run in the background: QEMU (TCG, one vCPU) keeps one core busy for
# minutes, and the builds and test runs after them use the other. Those are niced while a
# VM runs, so the guest keeps its pace (its scenarios time a reopening). Output of a
# background job: $BUILD_ROOT/background-NAME.out, its ctest log as run_ctest's.
BACKGROUND=()
start_background() {
  local name=$1
  shift
  say "in the background from now: $name (its output: $BUILD_ROOT/background-$name.out)"
  ("$@") >"$BUILD_ROOT/background-$name.out" 2>&1 &
  BACKGROUND+=("$name:$!")
  NICE=(nice -n 10)
}
wait_background() {
  local entry
  for entry in "${BACKGROUND[@]}"; do
    say "waiting for the background job ${entry%%:*}"
    wait "${entry##*:}" || echo "0 0 0 died" >"$RESULTS_DIR/${entry%%:*}-job"
  done
  BACKGROUND=()
  NICE=()
}
stop_background() {
  local entry
  for entry in "${BACKGROUND[@]}"; do kill_tree "${entry##*:}"; done
}
kill_tree() {
  local child
  for child in $(pgrep -P "$1" || true); do kill_tree "$child"; done
  kill "$1" 2>/dev/null || true
}

# Every VM test, one VM at a time (each takes a core, and they share the HIL cache), in
# one background job beside the builds and test runs of the foreground:
#   1. the host VM tests, as soon as the host build is there;
#   2. what the aarch64 VM tests need made once, which needs neither the aarch64 build nor
#      its tests: the arm64 kernel's modules (tests/hil/setup.sh arm64, about 100 s of
#      compiling) and the arm64 Debian root the package test installs into
#      (tests/package/arm64_root.sh, about 280 s, most of it dpkg in a TCG guest). Made
#      here they wait in the HIL cache, and the aarch64 VM tests' hil.setup and
#      package.arm64_root find them made (seconds) instead of spending those minutes at
#      the end of the run. The verdict on them stays with those two CTest tests: a failure
#      here is met again there and reported by them, so it is only noted here;
#   3. the aarch64 VM tests, once the foreground has built aarch64 (the file
#      $AARCH64_BUILT says so): they boot an arm64 kernel in qemu-system-aarch64 with the
#      cross-built binaries (the rest run under qemu-user), package.deb_arm64 too (the
#      arm64 .deb installed in the arm64 Debian root in the VM).
# The VM tests (label hil) get one more try when they fail: libcamera 0.0.3 under QEMU TCG
# hung once in 16 runs (docs/DRIVERS.md), and a hang is not a finding about skyloc. A real
# failure fails both tries. Not the host's package test (label package, tests/package): 2.5
# min and ~60 MB from the archive at every run; ctest -L package runs it
# (docs/PACKAGING.md).
AARCH64_BUILT="$BUILD_ROOT/aarch64.built"
vm_tests() {
  local cache="$BUILD_ROOT/hil-cache" rc=0 start
  # After cross_deps, always: the VM set-ups install a missing host package themselves
  # (tests/hil/setup.sh), and two apt-get runs at once would fail on dpkg's lock; and the
  # arm64 kernel modules are cross-compiled. It ends long before the host build does.
  await_cross_deps || rc=$?
  phase "host VM tests" run_ctest host-vm "$BUILD_ROOT/host/tests/hil" -L hil --repeat until-pass:2
  start=$SECONDS
  [ "$rc" -ne 0 ] || "$ROOT/tests/hil/setup.sh" arm64 "$cache" || rc=$?
  # The package test exists only with lintian and mmdebstrap (tests/hil/CMakeLists.txt).
  if [ "$rc" -eq 0 ] && command -v lintian >/dev/null && command -v mmdebstrap >/dev/null; then
    "$ROOT/tests/package/arm64_root.sh" "$cache" || rc=$?
  fi
  note_phase "arm64 VM set-up" "$start"
  [ "$rc" -eq 0 ] || say "the arm64 VM set-up exited $rc here; the aarch64 VM tests try it again and report it"
  start=$SECONDS
  while [ ! -e "$AARCH64_BUILT" ]; do sleep 2; done
  note_phase "waiting for aarch64" "$start"
  phase "aarch64 VM tests" run_ctest aarch64-vm "$BUILD_ROOT/aarch64/tests/hil" -L hil --repeat until-pass:2
}

cmd_test() {
  local start=$SECONDS wait_start
  rm -rf "$RESULTS_DIR"
  mkdir -p "$RESULTS_DIR"
  # A failure or Ctrl-C in the foreground stops the VMs too.
  trap stop_background EXIT
  rm -f "$AARCH64_BUILT" "$CROSS_READY" "$CROSS_FAILED"
  phase "packages" deps host
  start_background cross cross_deps
  phase "host build" configure_and_build host
  start_background vm vm_tests
  # x86-64 runs each test once: the ASan+UBSan build runs every test but the VM ones (those
  # boot a guest with the host build's binaries) and the long soak runs; the plain host
  # build runs those, the fuzz targets and the cases labelled native, whose subject the
  # sanitizers change (allocation counting, an impossible allocation, mlockall:
  # tests/CMakeLists.txt). Both ran everything before, the same cases twice on one
  # architecture, about 200 s of the run.
  phase "host tests" run_ctest host "$BUILD_ROOT/host" -L "native|slow|fuzz" -LE "hil|package"
  phase "asan build" configure_and_build asan
  # The aarch64 and armhf builds run every test but the VM ones and the soak runs too.
  phase "asan tests" run_ctest asan "$BUILD_ROOT/asan" -LE "hil|slow"
  # ThreadSanitizer over what runs threads: the recorder's writer thread and its queue,
  # and eval's fork-join (the batch matcher and the descriptors). Not cli.firmware_modes:
  # it expects a recording without drops, and TSan slows the writer below the camera.
  # (The libcamera completion path runs in the VM only: docs/DRIVERS.md.)
  # Only the programs those tests run are built: SpscQueue in the platform tests,
  # FrameRecorder in the firmware tests, ParallelFor and BlockedSeqSlamThreads in the tools
  # tests, and skyloc with make_eval_datasets for cli.eval_*. (A test executable left out
  # here would be registered as <name>_NOT_BUILT, which the -R filter does not pick.)
  phase "tsan build" configure_and_build tsan skyloc_platform_tests skyloc_firmware_tests \
    skyloc_tools_tests skyloc make_eval_datasets
  phase "tsan tests" run_ctest tsan "$BUILD_ROOT/tsan" \
    -R "SpscQueue|FrameRecorder|ParallelFor|BlockedSeqSlamThreads|^cli[.]eval_(batch|streaming)$"
  wait_start=$SECONDS
  await_cross_deps || die "the ARM builds' packages or sysroots could not be installed (its output: $BUILD_ROOT/background-cross.out)"
  note_phase "waiting for ARM deps" "$wait_start"
  phase "aarch64 build" configure_and_build aarch64
  touch "$AARCH64_BUILT"
  # The slow soak runs are the host build's job.
  phase "aarch64 tests" run_ctest aarch64 "$BUILD_ROOT/aarch64" -LE "slow|hil"
  # 32-bit ARM (Raspberry Pi OS 32-bit, ARMv7 boards): what only a 32-bit target shows
  # (size_t and off_t of 32 bits, long double = double), under qemu-arm. No VM for it.
  phase "armhf build" configure_and_build armhf
  phase "armhf tests" run_ctest armhf "$BUILD_ROOT/armhf" -LE "slow|hil"
  wait_background
  rm -f "$AARCH64_BUILT" "$CROSS_READY" "$CROSS_FAILED"
  trap - EXIT
  summarise_results $((SECONDS - start))
}

# The closing lines: each phase's wall time (the background ones overlap what follows
# them), the failing runs, and the total CI reads: "N passed, N failed, N skipped".
summarise_results() {
  local seconds=$1 f passed failed skipped verdict
  local total_passed=0 total_failed=0 total_skipped=0
  for f in "$RESULTS_DIR"/*; do
    [ "$(basename "$f")" = phases ] && continue
    read -r passed failed skipped verdict <"$f"
    total_passed=$((total_passed + passed))
    total_failed=$((total_failed + failed))
    total_skipped=$((total_skipped + skipped))
  done
  echo "phases (wall time; the VM tests ran beside the phases after them):"
  sed 's/^/  /' "$RESULTS_DIR/phases"
  say "all test runs took $seconds s ($((seconds / 60)) min $((seconds % 60)) s)"
  local failing
  failing=$(failed_runs)
  [ -z "$failing" ] || echo "failing runs: $failing"
  report_failed_tests
  # CI reads this closing line.
  echo "total: ${total_passed} passed, ${total_failed} failed, ${total_skipped} skipped"
  [ -z "$failing" ]
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

# The Debian package of a Release build (packaging/make-deb.sh, docs/PACKAGING.md),
# checked by lintian: an error or an unexplained warning fails.
cmd_package() {
  local kind=${1:-host} arch sysroot=()
  case "$kind" in
    host) arch=$(dpkg --print-architecture) ;;
    aarch64) arch=arm64 sysroot=("$BUILD_ROOT/sysroot-arm64") ;;
    armhf) arch=armhf sysroot=("$BUILD_ROOT/sysroot-armhf") ;;
    *) die "unknown package kind '$kind' (host, aarch64, armhf)" ;;
  esac
  deps "$kind"
  configure_and_build "package-$kind"
  local deb
  deb=$("$ROOT/packaging/make-deb.sh" "$BUILD_ROOT/package-$kind/app/skyloc" "$arch" "$BUILD_ROOT" "${sysroot[@]}") ||
    die "packaging failed for $kind"
  say "lintian $deb"
  # lintian leaves its mldbm-elf-* databases in TMPDIR: keep them in the build folder.
  local lintian_tmp="$BUILD_ROOT/package-$kind/lintian-tmp"
  rm -rf "$lintian_tmp"
  mkdir -p "$lintian_tmp"
  TMPDIR="$lintian_tmp" lintian --fail-on error,warning "$deb" || die "lintian rejects $deb (above): fix it, or override a tag with its reason in packaging/lintian-overrides"
  rm -rf "$lintian_tmp"
  # An ARM package cannot be installed on this machine (no binfmt_misc for its maintainer
  # scripts; the aarch64 build's package.deb_arm64 installs an arm64 one in the arm64 VM,
  # docs/PACKAGING.md); its binary at least runs from the package under qemu-user.
  if [ ${#sysroot[@]} -gt 0 ]; then
    local qemu=qemu-aarch64-static unpacked="$BUILD_ROOT/package-$kind/unpacked" version
    if [ "$kind" = armhf ]; then qemu="qemu-arm-static"; fi
    rm -rf "$unpacked"
    dpkg-deb -x "$deb" "$unpacked"
    version=$("$qemu" -L "${sysroot[0]}" "$unpacked/usr/bin/skyloc" --version) ||
      die "the packed $arch skyloc does not run under $qemu -L ${sysroot[0]}"
    rm -rf "$unpacked"
    say "packed binary under $qemu: $version"
  fi
  say "built $deb ($(du -h "$deb" | cut -f1)); on the robot: apt install ./$(basename "$deb")"
}

# Only what the skyloc executable needs: its packages, its target. ./skyloc.sh test later
# builds the rest in the same folder.
cmd_demo() {
  deps demo
  configure_and_build demo skyloc
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
    package) cmd_package "$@" ;;
    hil)
      local kind=${1:-host}
      case "$kind" in host | aarch64) ;; *) die "hil runs for host or aarch64, not '$kind'" ;; esac
      deps "$kind"
      configure_and_build "$kind"
      rm -rf "$RESULTS_DIR"
      run_ctest "$kind-vm" "$BUILD_ROOT/$kind/tests/hil" -L hil
      [ -z "$(failed_runs)" ] || die "hil tests failed (console logs: $BUILD_ROOT/$kind/hil-logs/)"
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
