# End to end: a libcamera camera (vimc) pulled out under `skyloc repeat`, and the
# restart that brings the robot back. libcamera 0.0.3 cannot reopen a lost camera inside
# the process (drivers/libcamera_camera.h, "Unplug"), so skyloc must exit cleanly (status
# 1, an error naming the camera, never an abort or a crash inside libcamera, the status
# lines safe and released) and the service manager restarts it (config/skyloc.service:
# Restart=on-failure, RestartSec=2); here the script plays the service manager. Passes
# when a route taught through libcamera is repeated, the unplug ends repeat that way, and
# the restarted repeat runs again once vimc is bound back.
# shellcheck source=tests/hil/guest/lib.sh
. /hil/tests/lib.sh

SKYLOC=/hil/bin/skyloc
[ -x "$SKYLOC" ] || pending "skyloc is not in this image"
ls /hil/lib/libcamera.so.* >/dev/null 2>&1 || pending "this build has no libcamera driver"

VDRV=/sys/bus/platform/drivers/vimc
VDEV=
for d in "$VDRV"/vimc*; do [ -L "$d" ] && VDEV=${d##*/}; done
[ -n "$VDEV" ] || {
  bad "no vimc platform device bound in $VDRV"
  finish_scenario
}
CONFIG=/tmp/skyloc_libcamera.toml
ROUTE=/tmp/libcamera_route.db
# vimc through libcamera 0.0.3 offers 636 columns, not 640 (its debayer crops).
camera_config libcamera first 636 200 >"$CONFIG"
status_gpio_config >>"$CONFIG"
wait_json() { # FILE COUNT SECONDS: until FILE has COUNT JSON lines or skyloc exits
  i=0
  while [ "$(json_lines "$1")" -lt "$2" ] && kill -0 "$skyloc" 2>/dev/null && [ "$i" -lt "$(($3 * 10))" ]; do
    sleep 0.1
    i=$((i + 1))
  done
  [ "$(json_lines "$1")" -ge "$2" ]
}
udev_stub_start

echo "teach 20 frames through libcamera (vimc)"
if "$SKYLOC" teach --route "$ROUTE" --config "$CONFIG" --frames 20 >/tmp/lc-teach.out 2>/tmp/lc-teach.err; then
  ok "teach exited 0 ($(json_lines /tmp/lc-teach.out) frames)"
else
  bad "teach exited non-zero"
  sed 's/^/       | /' /tmp/lc-teach.err | grep -v ' INFO \| WARN ' | tail -n 8
  udev_stub_stop
  finish_scenario
fi

echo "repeat, then unplug vimc ($VDEV unbound)"
"$SKYLOC" repeat --route "$ROUTE" --config "$CONFIG" >/tmp/lc-repeat.out 2>/tmp/lc-repeat.err &
skyloc=$!
if wait_json /tmp/lc-repeat.out 5 60; then ok "repeat runs ($(json_lines /tmp/lc-repeat.out) frames)"; else
  bad "repeat printed $(json_lines /tmp/lc-repeat.out) frames in 60 s"
fi
echo "$VDEV" >"$VDRV/unbind"
if ! wait_gone "$skyloc" 30; then
  bad "repeat still running 30 s after the unplug"
  kill -9 "$skyloc"
fi
wait "$skyloc"
rc=$?
expect_eq "repeat exit status after the unplug (1: an error, not a signal)" "$rc" 1
if grep -q "camera libcamera:.*lost" /tmp/lc-repeat.err; then
  ok "said why: $(grep -m 1 'lost' /tmp/lc-repeat.err | cut -c1-160)"
else
  bad "no error naming the lost camera"
  sed 's/^/       | /' /tmp/lc-repeat.err | grep -v ' INFO \| WARN ' | tail -n 8
fi
expect_eq "status lines after the exit (safe)" "$(status_levels)" 000
expect_eq "status lines released" "$(lines_held_by_skyloc 2,4p)" 0

echo "plug it back ($VDEV bound) and restart, as systemd does after RestartSec"
echo "$VDEV" >"$VDRV/bind"
sleep 2
"$SKYLOC" repeat --route "$ROUTE" --config "$CONFIG" >/tmp/lc-restart.out 2>/tmp/lc-restart.err &
skyloc=$!
if wait_json /tmp/lc-restart.out 5 60; then
  ok "the restarted repeat runs ($(json_lines /tmp/lc-restart.out) frames)"
else
  bad "the restarted repeat printed $(json_lines /tmp/lc-restart.out) frames in 60 s"
  sed 's/^/       | /' /tmp/lc-restart.err | grep -v ' INFO \| WARN ' | tail -n 8
fi
stop_skyloc "$skyloc" /tmp/lc-restart.err
expect_eq "restarted repeat exit status after SIGTERM" "$stop_rc" 0
udev_stub_stop
finish_scenario
