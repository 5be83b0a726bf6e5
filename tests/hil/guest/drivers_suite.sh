# The driver suites' real-driver instances (camera compliance: V4l2 and Libcamera; GPIO
# status output: Gpiod*) against vivid, vimc and gpio-sim, with the environment contract
# of docs/DRIVERS.md. On the build machine those instances skip (no devices); here a
# skipped real-driver instance is a failure: the VM exists to run them.
# shellcheck source=tests/hil/guest/lib.sh
. /hil/tests/lib.sh

T=/hil/bin/skyloc_drivers_tests
if [ ! -x "$T" ]; then
  bad "$T is not in the image (run.sh --bin)"
  finish_scenario
fi

export SKYLOC_TEST_GPIOCHIP="$HIL_GPIOCHIP"
export SKYLOC_TEST_GPIO_LINES=0,1,2
export SKYLOC_TEST_GPIO_INPUT_LINE=7
export SKYLOC_TEST_GPIO_SIM_DIR="$HIL_GPIO_SIM_DIR"

# A build without libcamera (-DSKYLOC_WITH_LIBCAMERA=OFF) has no libcamera instance to run:
# it is left out, visibly.
if ls /hil/lib/libcamera.so.* >/dev/null 2>&1; then
  export SKYLOC_TEST_LIBCAMERA_CAMERA=first
else
  echo "  (this build has no libcamera driver: the Libcamera instance is not required)"
fi

# Each instance runs in its own process, so that a crash in one (an abort inside
# libcamera, say) does not hide the results of the others. The simulated instances and
# the unit tests are the host's business (label unit); only real drivers run here.
echo "V4L2 camera on vivid (by path)"
export SKYLOC_TEST_V4L2_DEVICE="$HIL_VIVID_VIDEO" SKYLOC_TEST_V4L2_SIZE=640x480
run_suite vivid '*/V4l2' V4l2

echo "V4L2 camera on vivid (by driver:card name)"
card=$(v4l2-ctl -d "$HIL_VIVID_VIDEO" --info | sed -n 's/^[[:space:]]*Card type *: //p')
export SKYLOC_TEST_V4L2_DEVICE="vivid:$card"
run_suite vivid-by-name '*OpenStartCaptureStopClose*/V4l2' V4l2

echo "V4L2 camera on vimc's RGB/YUV Capture node (graph set up with media-ctl)"
if vimc_configure_rgb 640 480 >/tmp/media-ctl.log 2>&1; then
  ok "vimc graph configured for RGB24 640x480"
  export SKYLOC_TEST_V4L2_DEVICE="$HIL_VIMC_RGB"
  run_suite vimc-v4l2 '*/V4l2' V4l2
else
  bad "media-ctl could not configure vimc"
  sed 's/^/    /' /tmp/media-ctl.log
fi
unset SKYLOC_TEST_V4L2_DEVICE SKYLOC_TEST_V4L2_SIZE

if [ -n "$SKYLOC_TEST_LIBCAMERA_CAMERA" ]; then
  echo "libcamera camera on vimc (and [camera] fps through FrameDurationLimits)"
  run_suite vimc-libcamera '*/Libcamera:LibcameraFrameRate.*' Libcamera
fi

echo "GPIO status output on gpio-sim"
run_suite gpio-sim '*/Gpiod*' Gpiod

# Everything else in the binary, with every device above named. On the host some of these
# may skip for want of a device; here none may: a new real-driver test that skips in the
# VM too would otherwise never run anywhere. (V4l2Unplug and LibcameraUnplug have their
# own scenario.)
echo "the rest of the suite, every device named"
export SKYLOC_TEST_V4L2_DEVICE="$HIL_VIVID_VIDEO" SKYLOC_TEST_V4L2_SIZE=640x480
# Left out: the device instances (run above; the IIO IMU ones in the imu_iio scenario) and
# the one test that reads a file from the source tree (config/), which the guest does not
# have; the host build runs it.
rest='-*/V4l2:*/Libcamera:LibcameraFrameRate.*:*/Gpiod*:*/Iio:*/IioPolling:V4l2Unplug.*:LibcameraUnplug.*:CameraFile.ShippedExampleLoads'
"$T" --gtest_filter="$rest" --gtest_color=no >/tmp/suite-rest.log 2>&1
rc=$?
if [ "$rc" -eq 0 ]; then ok "rest of the suite exited 0 ($(grep -c '^\[       OK \]' /tmp/suite-rest.log) passed)"; else
  bad "rest of the suite exited $rc"
  grep -E '^\[  FAILED  \].*ms\)$' /tmp/suite-rest.log | sed 's/^/       | /'
fi
skipped=$(grep -c '^\[  SKIPPED \] .* (' /tmp/suite-rest.log)
if [ "$skipped" -eq 0 ]; then ok "nothing skipped inside the VM"; else
  bad "$skipped test(s) skipped inside the VM: give them their device here (tests/hil/guest/drivers_suite.sh, docs/HIL.md)"
  grep '^\[  SKIPPED \] .* (' /tmp/suite-rest.log | sed 's/^/       | /'
fi

finish_scenario
