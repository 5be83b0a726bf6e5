# Baseline: the kernel's test drivers work with Debian's own tools, before any of our code
# is involved. If this fails, a failing driver suite is the VM's fault, not ours.
# shellcheck source=tests/hil/guest/lib.sh
. /hil/tests/lib.sh

echo "vivid (V4L2 webcam emulation)"
expect_node -c "$HIL_VIVID_VIDEO" "vivid capture node"
echo "vimc (media-controller pipeline)"
expect_node -c "$HIL_VIMC_MEDIA" "vimc media node"
expect_node -c "$HIL_VIMC_RAW0" "vimc Raw Capture 0 node"
expect_node -c "$HIL_VIMC_RGB" "vimc RGB/YUV Capture node"
echo "gpio-sim"
expect_node -c "/dev/$HIL_GPIOCHIP" "gpio-sim chip"
expect_node -d "$HIL_GPIO_SIM_DIR" "gpio-sim sysfs folder"

# An unrequested gpio-sim line reads back its pull: checks the simulator's sysfs side.
echo pull-up >"$HIL_GPIO_SIM_DIR/sim_gpio7/pull"
expect_eq "sim_gpio7 follows pull-up" "$(cat "$HIL_GPIO_SIM_DIR/sim_gpio7/value")" 1
echo pull-down >"$HIL_GPIO_SIM_DIR/sim_gpio7/pull"
expect_eq "sim_gpio7 follows pull-down" "$(cat "$HIL_GPIO_SIM_DIR/sim_gpio7/value")" 0

echo "vivid streaming with v4l2-ctl"
check "vivid reports driver vivid" sh -c "v4l2-ctl -d $HIL_VIVID_VIDEO --info | grep -q 'Driver name *: vivid'"
check "vivid offers GREY and YUYV" sh -c "v4l2-ctl -d $HIL_VIVID_VIDEO --list-formats | grep -q GREY &&
  v4l2-ctl -d $HIL_VIVID_VIDEO --list-formats | grep -q YUYV"
check "vivid streams 4 YUYV 640x480 frames" v4l2-ctl -d "$HIL_VIVID_VIDEO" \
  --set-fmt-video=width=640,height=480,pixelformat=YUYV --stream-mmap=3 --stream-count=4 \
  --stream-to=/tmp/vivid.yuyv
expect_eq "vivid frame bytes" "$(file_size /tmp/vivid.yuyv)" $((4 * 640 * 480 * 2))
rm -f /tmp/vivid.yuyv

echo "vimc raw capture with media-ctl + v4l2-ctl"
# The sensor pad and the capture node must agree on a Bayer format, or STREAMON fails
# with EPIPE (media_pipeline_start validates every enabled link).
check "media-ctl sets Sensor A to SRGGB8 640x480" media-ctl -d "$HIL_VIMC_MEDIA" \
  -V '"Sensor A":0[fmt:SRGGB8_1X8/640x480]'
check "vimc Raw Capture 0 streams 3 RGGB frames" v4l2-ctl -d "$HIL_VIMC_RAW0" \
  --set-fmt-video=width=640,height=480,pixelformat=RGGB --stream-mmap=3 --stream-count=3 \
  --stream-to=/tmp/vimc.raw
expect_eq "vimc frame bytes" "$(file_size /tmp/vimc.raw)" $((3 * 640 * 480))
rm -f /tmp/vimc.raw
check "media-ctl configures the RGB pipeline" vimc_configure_rgb 640 480
check "vimc RGB/YUV Capture streams 3 RGB24 frames" v4l2-ctl -d "$HIL_VIMC_RGB" \
  --stream-mmap=3 --stream-count=3 --stream-to=/tmp/vimc.rgb
expect_eq "vimc RGB frame bytes" "$(file_size /tmp/vimc.rgb)" $((3 * 640 * 480 * 3))
rm -f /tmp/vimc.rgb

if have cam; then
  echo "libcamera (vimc pipeline handler) with cam"
  check "cam lists a vimc camera" sh -c "cam -l 2>&1 | grep -q 'platform/vimc'"
  check "cam captures 3 640x480 frames from camera 1" sh -c \
    "cam -c 1 -s role=viewfinder,width=640,height=480 --capture=3 2>&1 | grep -c 'seq:' | grep -qx 3"
else
  # The arm64 image has no libcamera: the cross build has no arm64 libcamera either.
  echo "libcamera: not in the $HIL_ARCH image"
fi

echo "gpio-sim through libgpiod tools"
check "gpiodetect lists the chip" sh -c "gpiodetect | grep -q '^$HIL_GPIOCHIP .*(8 lines)'"
check "gpioinfo shows the named line" sh -c "gpioinfo $HIL_GPIOCHIP | grep -q '\"status-lost\"'"
gpioset --mode=signal "$HIL_GPIOCHIP" 0=1 2=0 &
setter=$!
# Wait until gpioset holds the lines (a loaded TCG guest can take a while to start it).
i=0
while [ "$i" -lt 100 ] && ! gpioinfo "$HIL_GPIOCHIP" | grep -q '"gpioset"'; do
  sleep 0.1
  i=$((i + 1))
done
expect_eq "gpioset line 0 high, read back from sim_gpio0" "$(cat "$HIL_GPIO_SIM_DIR/sim_gpio0/value")" 1
expect_eq "gpioset line 2 low, read back from sim_gpio2" "$(cat "$HIL_GPIO_SIM_DIR/sim_gpio2/value")" 0
kill "$setter"
wait "$setter" 2>/dev/null
echo pull-up >"$HIL_GPIO_SIM_DIR/sim_gpio7/pull"
expect_eq "gpioget reads pull-up on line 7" "$(gpioget "$HIL_GPIOCHIP" 7)" 1
echo pull-down >"$HIL_GPIO_SIM_DIR/sim_gpio7/pull"
expect_eq "gpioget reads pull-down on line 7" "$(gpioget "$HIL_GPIOCHIP" 7)" 0

finish_scenario
