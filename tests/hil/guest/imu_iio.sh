# The IIO IMU driver (IioImu) against a real IIO device: the kernel's iio_dummy, built
# out-of-tree and patched into a still, level 6-axis IMU (tests/hil/iio_dummy_imu.patch),
# created through configfs, buffered through an hrtimer trigger. A baseline with the
# kernel's sysfs and character device first (no skyloc code), then the IMU compliance
# suite's real instances: Iio (buffer) and IioPolling (sysfs). Nothing may skip here.
# shellcheck source=tests/hil/guest/lib.sh
. /hil/tests/lib.sh

T=/hil/bin/skyloc_drivers_tests
CFG=$IIO_CONFIGFS
NAME=hilimu
TRIGGER=hiltrig

make_iio_imu "$NAME" "$TRIGGER"

# The device and trigger by name, as the driver finds them.
DEV=
for d in /sys/bus/iio/devices/iio:device*; do
  [ "$(cat "$d/name" 2>/dev/null)" = "$NAME" ] && DEV=$d
done
TRIG=
for d in /sys/bus/iio/devices/trigger*; do
  [ "$(cat "$d/name" 2>/dev/null)" = "$TRIGGER" ] && TRIG=$d
done
expect_node -d "$DEV" "IIO device $NAME:"
expect_node -d "$TRIG" "IIO trigger $TRIGGER:"
NODE=/dev/${DEV##*/}
expect_node -c "$NODE" "character device"

# --- baseline: the patched driver as the kernel exposes it ----------------------------
if [ -n "$DEV" ]; then
  expect_eq "in_accel_x/y/z_raw" "$(cat "$DEV/in_accel_x_raw") $(cat "$DEV/in_accel_y_raw") $(cat "$DEV/in_accel_z_raw")" "0 0 16399"
  expect_eq "in_anglvel_x/y/z_raw" "$(cat "$DEV/in_anglvel_x_raw") $(cat "$DEV/in_anglvel_y_raw") $(cat "$DEV/in_anglvel_z_raw")" "10 -20 30"
  expect_eq "in_accel_scale" "$(cat "$DEV/in_accel_scale")" "0.000598"
  expect_eq "in_anglvel_scale" "$(cat "$DEV/in_anglvel_scale")" "0.001000"
  expect_eq "in_accel_z_type" "$(cat "$DEV/scan_elements/in_accel_z_type")" "le:s16/16>>0"
  expect_eq "in_timestamp_type" "$(cat "$DEV/scan_elements/in_timestamp_type")" "le:s64/64>>0"
  # Six 16-bit axes and the 64-bit timestamp: 12 bytes, padded to 16, + 8 = 24 a scan.
  for ch in in_voltage0 in_voltage1-voltage2 in_voltage3-voltage4; do
    echo 0 >"$DEV/scan_elements/${ch}_en"
  done
  for ch in in_accel_x in_accel_y in_accel_z in_anglvel_x in_anglvel_y in_anglvel_z in_timestamp; do
    echo 1 >"$DEV/scan_elements/${ch}_en"
  done
  echo "$TRIGGER" >"$DEV/trigger/current_trigger"
  echo 100 >"$TRIG/sampling_frequency"
  echo 1 >"$DEV/buffer/enable"
  bytes=$(timeout 10 dd if="$NODE" bs=240 count=1 2>/dev/null | wc -c | tr -d ' ')
  echo 0 >"$DEV/buffer/enable"
  echo >"$DEV/trigger/current_trigger"
  case "$bytes" in
    '' | 0) bad "no scan read from $NODE with the hrtimer trigger at 100 Hz" ;;
    *) if [ $((bytes % 24)) -eq 0 ]; then ok "buffer read $bytes bytes (whole 24-byte scans)"; else
      bad "buffer read $bytes bytes, not whole 24-byte scans"
    fi ;;
  esac
fi

# --- the driver suite's real IIO instances --------------------------------------------
if [ ! -x "$T" ]; then
  bad "$T is not in the image (run.sh --bin)"
  finish_scenario
fi
export SKYLOC_TEST_IIO_DEVICE=$NAME
export SKYLOC_TEST_IIO_TRIGGER=$TRIGGER
export SKYLOC_TEST_IIO_CONFIGFS=$CFG/devices/dummy/$NAME
echo "IIO IMU, buffered through the hrtimer trigger"
run_suite iio-buffer '*/Iio' Iio
echo "IIO IMU, sysfs polling"
run_suite iio-polling '*/IioPolling' IioPolling
# The vanish case removed and recreated the device: it must be back.
back=
for d in /sys/bus/iio/devices/iio:device*; do
  [ "$(cat "$d/name" 2>/dev/null)" = "$NAME" ] && back=$d
done
expect_node -d "$back" "IIO device $NAME after the vanish/revive cases:"

finish_scenario
