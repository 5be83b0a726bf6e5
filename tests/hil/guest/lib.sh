# Shared helpers for the guest scenarios (sourced; busybox sh).
# shellcheck disable=SC1091 # written by /init in the guest
. /run/hil.env
failures=0
ok() { echo "  ok   $*"; }
bad() {
  echo "  FAIL $*"
  failures=$((failures + 1))
}
# check DESCRIPTION COMMAND...: runs the command, its output indented, and counts a failure.
check() {
  desc=$1
  shift
  if out=$("$@" 2>&1); then ok "$desc"; else
    bad "$desc: '$*' exited $?"
    echo "$out" | tail -n 15 | sed 's/^/       | /'
  fi
}
# expect_eq DESCRIPTION ACTUAL EXPECTED
expect_eq() {
  if [ "$2" = "$3" ]; then ok "$1 ($2)"; else bad "$1: got '$2', expected '$3'"; fi
}
# expect_node -c|-d PATH DESCRIPTION
expect_node() {
  if [ -n "$2" ] && test "$1" "$2"; then ok "$3 $2"; else bad "$3 missing ('$2')"; fi
}
file_size() { wc -c <"$1" | tr -d ' '; }
# A scenario whose subject is not in this build yet: SKIPPED (77), never passed; after a
# failed check it fails instead.
pending() {
  echo "  PENDING: $*"
  [ "$failures" -eq 0 ] && exit 77
  finish_scenario
}
# The three status lines (gpio-sim lines 0-2) as read back, line 0 first: "100".
status_levels() {
  echo "$(cat "$HIL_GPIO_SIM_DIR/sim_gpio0/value")$(cat "$HIL_GPIO_SIM_DIR/sim_gpio1/value")$(cat "$HIL_GPIO_SIM_DIR/sim_gpio2/value")"
}
# lines_held_by_skyloc SED_SCRIPT: how many of the gpioinfo lines that SED_SCRIPT prints
# ('2,4p': lines 0-2, the status lines) are requested by consumer "skyloc".
lines_held_by_skyloc() {
  gpioinfo "$HIL_GPIOCHIP" | sed -n "$1" | grep -c '"skyloc"'
}
# camera_config KIND DEVICE WIDTH ROUTE_FRAMES: the [camera], [descriptor] and [capacities]
# tables of the firmware scenarios (480 rows, frames within a second, 16 bands).
camera_config() {
  printf '[camera]\nkind = "%s"\ndevice = "%s"\nwidth = %s\nheight = 480\nframe_timeout_ms = 1000\n\n[descriptor]\nbands = 16\n\n[capacities]\nroute_frames = %s\n\n' "$1" "$2" "$3" "$4"
}
# make_iio_imu NAME TRIGGER: the kernel's iio_dummy, patched into a still, level 6-axis IMU
# (tests/hil/iio_dummy_imu.patch), as device NAME, and an hrtimer trigger TRIGGER, both made
# in configfs ($IIO_CONFIGFS).
IIO_CONFIGFS=/sys/kernel/config/iio
make_iio_imu() {
  check "modprobe iio_dummy" modprobe iio_dummy
  check "modprobe iio-trig-hrtimer" modprobe iio-trig-hrtimer
  check "iio_dummy device $1 created in configfs" mkdir "$IIO_CONFIGFS/devices/dummy/$1"
  check "hrtimer trigger $2 created in configfs" mkdir "$IIO_CONFIGFS/triggers/hrtimer/$2"
}
# The [status] table of a firmware configuration: gpio-sim lines 0-2, one per state.
status_gpio_config() {
  printf '[status]\nkind = "gpio"\nchip = "%s"\nline_lost = 0\nline_searching = 1\nline_localised = 2\nencoding = "per-state"\n' "$HIL_GPIOCHIP"
}
# udevd's part, for which this guest has no daemon: a udev database entry for every
# character device, new ones included (libcamera's enumerator skips nodes without one,
# and vimc's nodes come back with new numbers after a bind). udev_stub_start runs it in
# the background, udev_stub_stop ends it.
udev_stub_start() {
  (
    while :; do
      for d in /sys/dev/char/*; do
        [ -e /run/udev/data/c"${d##*/}" ] || echo "I:1" >/run/udev/data/c"${d##*/}"
      done
      sleep 0.2
    done
  ) &
  udev_stub=$!
}
udev_stub_stop() { kill "$udev_stub" 2>/dev/null; }
have() { command -v "$1" >/dev/null 2>&1; }
json_lines() { # FILE: how many JSON lines (frames) skyloc has printed into FILE
  n=$(grep -c '^{' "$1" 2>/dev/null)
  echo "${n:-0}"
}
wait_gone() { # PID SECONDS: 0 when the process has exited within the time
  i=0
  while kill -0 "$1" 2>/dev/null; do
    i=$((i + 1))
    [ "$i" -gt $(($2 * 10)) ] && return 1
    sleep 0.1
  done
  return 0
}
# stop_skyloc PID ERRFILE: SIGTERM to a running skyloc, as systemd stops the service, and
# its exit status in $stop_rc. The service gives it TimeoutStopSec=5 before SIGKILL
# (config/skyloc.service); a guest under TCG runs several times slower than the board, so
# the scenario allows 20 s. A process still there then is a failure, told with what each
# of its threads was doing (state, kernel wait channel, system call) and the end of its
# stderr, and is killed: a hang costs the scenario 20 s instead of its whole time limit.
stop_skyloc() {
  kill -TERM "$1" 2>/dev/null
  if ! wait_gone "$1" 20; then
    bad "skyloc (pid $1) still running 20 s after SIGTERM; its threads (name, state, wait channel, syscall):"
    # The state is the field after the name in parentheses, which may hold spaces.
    for t in /proc/"$1"/task/*; do
      echo "       | $(cat "$t/comm" 2>/dev/null) $(sed 's/.*) //' "$t/stat" 2>/dev/null | cut -d' ' -f1)" \
        "$(cat "$t/wchan" 2>/dev/null) $(cut -d' ' -f1 "$t/syscall" 2>/dev/null)"
    done
    grep -v ' INFO \| WARN ' "$2" | tail -n 8 | sed 's/^/       | /'
    kill -KILL "$1" 2>/dev/null
  fi
  wait "$1"
  # shellcheck disable=SC2034 # read by the scenarios that call this
  stop_rc=$?
}
# Exit status of a scenario: 0 when every check passed.
finish_scenario() {
  if [ "$failures" -eq 0 ]; then
    echo "  all checks passed"
    exit 0
  fi
  echo "  $failures check(s) failed"
  exit 1
}

# run_suite LABEL FILTER INSTANCES: runs the suite program $T; passes when it exits 0, no test of the
# listed instances (comma-separated parameter names) was skipped, and each of them passed
# at least one test.
run_suite() {
  label=$1
  filter=$2
  instances=$3
  out=/tmp/suite-$label.log
  echo "--- $label: $T --gtest_filter=$filter"
  "$T" --gtest_filter="$filter" --gtest_color=no >"$out" 2>&1
  rc=$?
  sed 's/^/    /' "$out"
  if [ "$rc" -eq 0 ]; then
    ok "$label: suite exited 0"
  elif [ "$rc" -gt 128 ]; then
    # Killed by a signal: the test that was running has no result line.
    bad "$label: suite killed by signal $((rc - 128)) during $(sed -n 's/^\[ RUN      \] //p' "$out" | tail -1)"
  else
    bad "$label: suite exited $rc"
  fi
  # Result lines of parameterised tests end in "/<instance> (N ms)" (passed, skipped) or
  # "/<instance>, where GetParam() = ..." (failed).
  for inst in $(echo "$instances" | tr ',' ' '); do
    passed=$(grep -c "^\[       OK \] .*/${inst}[A-Za-z]* (" "$out")
    failed=$(grep -c "^\[  FAILED  \] .*/${inst}[A-Za-z]*[ ,].*ms)$" "$out")
    skipped=$(grep -c "^\[  SKIPPED \] .*/${inst}[A-Za-z]* (" "$out")
    summary="$inst: $passed passed, $failed failed, $skipped skipped"
    if [ "$skipped" -ne 0 ]; then
      bad "$label: $summary (nothing may skip inside the VM: is the environment above wrong?)"
    elif [ "$passed" -eq 0 ] || [ "$failed" -ne 0 ]; then
      bad "$label: $summary"
    else
      ok "$label: $summary"
    fi
  done
}

# vimc's "RGB/YUV Capture" pipeline (Sensor A -> Debayer A -> Scaler -> capture) set to
# RGB24 WxH. Every enabled link is validated at STREAMON (EPIPE otherwise), including
# Sensor A -> Raw Capture 0, so that node gets the matching Bayer format too. The links
# are reset first: libcamera's vimc pipeline handler routes Sensor B -> Debayer B ->
# Scaler instead, and leaves the graph that way.
vimc_configure_rgb() { # WIDTH HEIGHT
  w=$1
  h=$2
  media-ctl -d "$HIL_VIMC_MEDIA" -r &&
    media-ctl -d "$HIL_VIMC_MEDIA" -l '"Debayer A":1->"Scaler":0[1]' &&
    media-ctl -d "$HIL_VIMC_MEDIA" -V "\"Sensor A\":0[fmt:SRGGB8_1X8/${w}x${h}]" &&
    media-ctl -d "$HIL_VIMC_MEDIA" -V "\"Debayer A\":0[fmt:SRGGB8_1X8/${w}x${h}]" &&
    media-ctl -d "$HIL_VIMC_MEDIA" -V "\"Debayer A\":1[fmt:RGB888_1X24/${w}x${h}]" &&
    media-ctl -d "$HIL_VIMC_MEDIA" -V "\"Scaler\":0[fmt:RGB888_1X24/${w}x${h}]" &&
    media-ctl -d "$HIL_VIMC_MEDIA" -V "\"Scaler\":1[fmt:RGB888_1X24/${w}x${h}]" &&
    v4l2-ctl -d "$HIL_VIMC_RAW0" -v "width=$w,height=$h,pixelformat=RGGB" &&
    v4l2-ctl -d "$HIL_VIMC_RGB" -v "width=$w,height=$h,pixelformat=RGB3"
}

# The Debian root on the virtio disk (/dev/vda: run.sh --disk or --snapshot-disk), made by
# tests/package/arm64_root.sh: debian_root_mount mounts it on $DEBIAN_ROOT with /dev,
# /proc and /sys inside (dpkg, apt and the maintainer scripts need them);
# in_debian_root runs a command of the root chrooted there with a plain Debian
# environment, not the guest's (LD_LIBRARY_PATH=/hil/lib and PATH=/hil/bin are for this
# initramfs's programs).
DEBIAN_ROOT=/mnt/debian
debian_root_mount() {
  # No udev here to load modules for new devices: the disk's and the file system's by
  # hand (ext4 asks the crypto API for crc32c at mount time, so that is named too).
  for m in virtio_mmio virtio_blk crc32c_generic ext4; do modprobe "$m" || return 1; done
  i=0
  while [ ! -b /dev/vda ] && [ $i -lt 50 ]; do
    sleep 0.1
    i=$((i + 1))
  done
  mkdir -p "$DEBIAN_ROOT" &&
    mount -t ext4 /dev/vda "$DEBIAN_ROOT" &&
    mount --bind /dev "$DEBIAN_ROOT/dev" &&
    mount -t proc proc "$DEBIAN_ROOT/proc" &&
    mount -t sysfs sysfs "$DEBIAN_ROOT/sys"
}
debian_root_umount() {
  umount "$DEBIAN_ROOT/sys" "$DEBIAN_ROOT/proc" "$DEBIAN_ROOT/dev" &&
    umount "$DEBIAN_ROOT"
}
# The root's own env, by its absolute path: this busybox prefers its applets to programs
# named without a path (chroot dpkg would run busybox's dpkg, sh its ash).
in_debian_root() {
  chroot "$DEBIAN_ROOT" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin HOME=/root LC_ALL=C \
    DEBIAN_FRONTEND=noninteractive "$@"
}
