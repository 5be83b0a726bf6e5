# End to end: the IIO IMU (iio_dummy as a still, level 6-axis IMU, made as imu_iio.sh makes
# it) unplugged and plugged back under `skyloc repeat` on the vivid camera. The device is
# taken away by removing its configfs folder and made again under the same name 1.7 s
# after skyloc noticed (about 1.8 s away in all).
# Passes when:
#   - with the IMU there, frames use its attitude (the gravity-aligned cap is on);
#   - after the unplug skyloc warns that frames are described as if level (the cap off)
#     and keeps printing frames;
#   - once the device is back, the cap is on again within a second of the re-add
#     (bound below), the outage and the reopen are counted in the SIGUSR1 table on stderr
#     and in the JSON lines' devices record;
#   - SIGTERM ends it with status 0 and every frame it counted is in the JSON lines.
# The camera is vivid, not the simulated camera: a simulated run stamps its frames with
# the run's time from 0, the IIO IMU its samples with CLOCK_MONOTONIC, so no sample would
# ever be at or before a frame and the cap would never turn on. vivid's buffers carry
# CLOCK_MONOTONIC timestamps, as a real camera's do.
# The predicates below are called through wait_for.
# shellcheck disable=SC2317
# shellcheck source=tests/hil/guest/lib.sh
. /hil/tests/lib.sh

SKYLOC=/hil/bin/skyloc
[ -x "$SKYLOC" ] || pending "skyloc is not in this image"

CFG=$IIO_CONFIGFS
NAME=hilimu
TRIGGER=hiltrig
make_iio_imu "$NAME" "$TRIGGER"
[ "$failures" -eq 0 ] || finish_scenario

card=$(v4l2-ctl -d "$HIL_VIVID_VIDEO" --info | sed -n 's/^[[:space:]]*Card type *: //p')
CONFIG=/tmp/skyloc_imu.toml
ROUTE=/tmp/imu_route.db
OUT=/tmp/imu-repeat.out
ERR=/tmp/imu-repeat.err
camera_config v4l2 "vivid:$card" 640 200 >"$CONFIG"
cat >>"$CONFIG" <<EOF
[attitude]
kind = "iio"
device = "$NAME"
trigger = "$TRIGGER"
rate_hz = 100.0
EOF

# The guest's CLOCK_MONOTONIC in seconds: /proc/uptime is CLOCK_BOOTTIME, the same clock
# in a guest that never suspends, to 10 ms (the frames' timestamps are CLOCK_MONOTONIC).
now_s() { cut -d ' ' -f 1 /proc/uptime; }
# "frame timestamp" of every per-frame JSON line of FILE.
frame_times() { sed -n 's/^{"schema":[0-9]*,"frame":\([0-9]*\),"timestamp":\([0-9.]*\),.*/\1 \2/p' "$1"; }
# How many times stderr said the cap went off (frames as if level) and came back.
offs() { grep -c 'frames are described as if level until it returns' "$ERR"; }
backs() { grep -c "attitude iio:$NAME is back at frame" "$ERR"; }
frame_lines() { grep -c '^{"schema":[0-9]*,"frame":' "$1"; }
# The newest devices record's IMU counter NAME (outages, reopens), or nothing.
json_imu_counter() {
  grep '^{"devices":' "$OUT" | tail -n 1 | sed -n "s/.*\"imu\":{[^}]*\"$1\":\([0-9]*\).*/\1/p"
}
# until COMMAND succeeds or SECONDS pass; 0 when it did. Stops waiting if skyloc exits.
wait_for() {
  secs=$1
  shift
  i=0
  while ! "$@"; do
    kill -0 "$skyloc" 2>/dev/null || return 1
    i=$((i + 1))
    [ "$i" -gt $((secs * 10)) ] && return 1
    sleep 0.1
  done
}

echo "teach 20 frames from vivid with the IIO IMU's attitude"
if "$SKYLOC" teach --route "$ROUTE" --config "$CONFIG" --frames 20 >/tmp/imu-teach.out 2>/tmp/imu-teach.err; then
  ok "teach exited 0 ($(json_lines /tmp/imu-teach.out) frames)"
else
  bad "teach exited non-zero"
  sed 's/^/       | /' /tmp/imu-teach.err | tail -n 10
  finish_scenario
fi

echo "repeat"
"$SKYLOC" repeat --route "$ROUTE" --config "$CONFIG" >"$OUT" 2>"$ERR" &
skyloc=$!
at_least_frames() { [ "$(json_lines "$OUT")" -ge "$1" ]; }
cap_on() { [ "$(offs)" -eq "$(backs)" ]; }
if wait_for 60 at_least_frames 10 && wait_for 10 cap_on; then
  ok "repeat runs with the cap on ($(json_lines "$OUT") frames)"
else
  bad "repeat printed $(json_lines "$OUT") frames, cap off $(offs) times, back $(backs) times"
  sed 's/^/       | /' "$ERR" | tail -n 10
fi
offs_before=$(offs)
frames_before=$(frame_lines "$OUT")

echo "unplug the IMU ($CFG/devices/dummy/$NAME removed)"
t_unplug=$(now_s)
check "device folder removed" rmdir "$CFG/devices/dummy/$NAME"
cap_off() { [ "$(offs)" -gt "$offs_before" ]; }
if wait_for 5 cap_off; then
  ok "cap off: $(grep 'described as if level' "$ERR" | tail -n 1 | cut -c1-150)"
else
  bad "no warning that frames are described as if level within 5 s of the unplug"
fi
# Back 1.7 s after the cap went off (it is seen within 0.1 s): between the reopen attempts
# 1.5 s and 3.1 s after the loss on a schedule doubling up to 2 s (the camera's), where the
# second would come 1.1-1.6 s after the re-add; the IMU's (capped at 500 ms) tries 1.7 s.
sleep 1.7
backs_before=$(backs)
t_before_mkdir=$(now_s)
check "device folder made again" mkdir "$CFG/devices/dummy/$NAME"
t_readd=$(now_s)
echo "  unplugged at ${t_unplug} s, made again at ${t_before_mkdir}..${t_readd} s (CLOCK_MONOTONIC)"
cap_back() { [ "$(backs)" -gt "$backs_before" ]; }
if wait_for 10 cap_back; then
  back_frame=$(grep "attitude iio:$NAME is back at frame" "$ERR" | tail -n 1 | sed 's/.* frame //')
  back_t=$(frame_times "$OUT" | sed -n "s/^$back_frame //p")
  gap=$(frame_times "$OUT" | awk -v f="$back_frame" '$1 == f { printf "%.3f", $2 - prev } { prev = $2 }')
  # From the start of the mkdir (the longer interval) to the timestamp of the first frame
  # with the cap on again. The bound is the second asked, plus the interval from the frame
  # before (the reopen is tried only when a frame asks for the attitude, so the first
  # frame captured after it is the first that can show it; under TCG vivid's frames come
  # 100-300 ms apart), plus 0.1 s for the first scan of the 100 Hz hrtimer trigger after
  # the buffer is enabled again and the 10 ms resolution of /proc/uptime.
  took=$(awk -v a="$back_t" -v b="$t_before_mkdir" 'BEGIN { printf "%.3f", a - b }')
  bound=$(awk -v g="$gap" 'BEGIN { printf "%.3f", 1.1 + g }')
  echo "  cap on again at frame $back_frame, timestamp $back_t s, $gap s after the frame before"
  if awk -v d="$took" -v b="$bound" 'BEGIN { exit !(d >= -0.05 && d <= b) }'; then
    ok "cap on again ${took} s after the re-add (bound 1.1 s + the frame interval $gap s)"
  else
    bad "cap on again ${took} s after the re-add (bound 1.1 s + the frame interval $gap s)"
  fi
else
  bad "the cap did not come back within 10 s of the re-add"
  sed 's/^/       | /' "$ERR" | tail -n 10
fi

echo "SIGUSR1: the counters table"
kill -USR1 "$skyloc"
table() { grep -q '^imu .*reopens' "$ERR"; }
if wait_for 5 table; then
  row=$(grep '^imu .*reopens' "$ERR" | tail -n 1)
  echo "  | $row"
  outages=$(echo "$row" | sed -n 's/.*outages \([0-9]*\).*/\1/p')
  reopens=$(echo "$row" | sed -n 's/.*reopens \([0-9]*\).*/\1/p')
  if [ "${outages:-0}" -ge 1 ] && [ "${reopens:-0}" -ge 1 ]; then
    ok "SIGUSR1 table counts the outage and the reopen (outages $outages, reopens $reopens)"
  else
    bad "SIGUSR1 table: outages '$outages', reopens '$reopens'; both should be >= 1"
  fi
else
  bad "no imu row in a SIGUSR1 table within 5 s"
  sed 's/^/       | /' "$ERR" | tail -n 10
fi
# The devices record comes once a second.
json_counted() {
  o=$(json_imu_counter outages)
  r=$(json_imu_counter reopens)
  [ "${o:-0}" -ge 1 ] && [ "${r:-0}" -ge 1 ]
}
if wait_for 5 json_counted; then
  ok "devices record counts them ($(grep '^{"devices":' "$OUT" | tail -n 1 | sed -n 's/.*"imu":\({[^}]*}\).*/\1/p'))"
else
  bad "devices record: outages '$(json_imu_counter outages)', reopens '$(json_imu_counter reopens)'"
fi
if [ "$(frame_lines "$OUT")" -gt "$frames_before" ]; then
  ok "frames went on through the outage ($(($(frame_lines "$OUT") - frames_before)) since the unplug)"
else
  bad "no frame since the unplug"
fi

stop_skyloc "$skyloc" "$ERR"
expect_eq "repeat exit status after SIGTERM" "$stop_rc" 0
counted=$(sed -n 's/^.*: \([0-9]*\) frames (.*/\1/p' "$ERR" | tail -n 1)
expect_eq "frames in the JSON lines = frames counted in the summary" "$(frame_lines "$OUT")" "$counted"
# Frame numbers only ever increase (a line is never repeated or out of order).
if frame_times "$OUT" | awk 'NR > 1 && $1 <= prev { exit 1 } { prev = $1 }'; then
  ok "frame numbers increase"
else
  bad "frame numbers go back"
fi
sed 's/^/       | /' "$ERR" | grep -v ' INFO ' | tail -n 12
finish_scenario
