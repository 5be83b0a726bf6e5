# End to end: the blink encoding moves with time, not with frames (docs/FIRMWARE.md, "The
# status lines between frames"). `skyloc repeat` runs from vivid at 2 fps with [status]
# encoding = "blink" on gpio-sim line 2. The route is taught from the same static test
# pattern, so no place in it is unique and every frame is LOST: a 100 ms flash every 2 s.
# The line is sampled from sysfs for 7 s. Passes when:
#   - every JSON line in that time says LOST;
#   - the line flashed at least twice, each flash shorter than a frame period (a blink
#     moved only by frames holds a flash until the next frame, 500 ms later, or skips it);
#   - flashes start about 2 s apart (phase-locked to the monotonic clock).
# While this skyloc has no V4L2 camera or GPIO status output, the scenario is SKIPPED.
# shellcheck source=tests/hil/guest/lib.sh
. /hil/tests/lib.sh

SKYLOC=/hil/bin/skyloc
[ -x "$SKYLOC" ] || pending "skyloc is not in this image"

card=$(v4l2-ctl -d "$HIL_VIVID_VIDEO" --info | sed -n 's/^[[:space:]]*Card type *: //p')
ROUTE=/tmp/blink_route.db
LINE=$HIL_GPIO_SIM_DIR/sim_gpio2/value
camera_config() { # FPS
  printf '[camera]\nkind = "v4l2"\ndevice = "vivid:%s"\nwidth = 640\nheight = 480\nfps = %s\nframe_timeout_ms = 2000\n\n' "$card" "$1"
  printf '[descriptor]\nbands = 16\n\n[capacities]\nroute_frames = 100\n\n'
  printf '[status]\nkind = "gpio"\nchip = "%s"\nline_lost = 0\nline_searching = 1\nline_localised = 2\nencoding = "blink"\n' "$HIL_GPIOCHIP"
}
camera_config 30 >/tmp/blink_teach.toml
camera_config 2 >/tmp/blink_repeat.toml

echo "teach 20 frames of vivid's test pattern"
rm -f "$ROUTE"
"$SKYLOC" teach --route "$ROUTE" --config /tmp/blink_teach.toml --frames 20 >/tmp/blink_teach.out 2>/tmp/blink_teach.err
rc=$?
if grep -q "not built into this skyloc" /tmp/blink_teach.err; then
  pending "$(head -n 1 /tmp/blink_teach.err)"
fi
if [ "$rc" -ne 0 ]; then
  bad "teach exited $rc"
  sed 's/^/       | /' /tmp/blink_teach.err | tail -n 10
  finish_scenario
fi
ok "teach exited 0"

echo "repeat at 2 fps, the blink line sampled for 7 s"
"$SKYLOC" repeat --route "$ROUTE" --config /tmp/blink_repeat.toml >/tmp/blink.out 2>/tmp/blink.err &
skyloc=$!
i=0
while ! grep -q '^{' /tmp/blink.out 2>/dev/null && kill -0 "$skyloc" 2>/dev/null && [ "$i" -lt 300 ]; do
  sleep 0.1
  i=$((i + 1))
done
if ! kill -0 "$skyloc" 2>/dev/null; then
  bad "repeat ended before its first frame"
  sed 's/^/       | /' /tmp/blink.err | tail -n 10
  finish_scenario
fi
# Hundredths of a second since boot.
now_cs() { tr -d . </proc/uptime | cut -d ' ' -f 1; }
lines_before=$(grep -c '^{' /tmp/blink.out)
end=$(($(now_cs) + 700))
samples=0
level=0
since=0
flashes=0
starts=
longest=0
while :; do
  t=$(now_cs)
  [ "$t" -ge "$end" ] && break
  v=$(cat "$LINE")
  samples=$((samples + 1))
  if [ "$v" = 1 ] && [ "$level" = 0 ]; then
    since=$t
    starts="$starts $t"
  elif [ "$v" = 0 ] && [ "$level" = 1 ]; then
    flashes=$((flashes + 1))
    [ $((t - since)) -gt "$longest" ] && longest=$((t - since))
  fi
  level=$v
done
frames=$(($(grep -c '^{' /tmp/blink.out) - lines_before))
stop_skyloc "$skyloc" /tmp/blink.err
rc=$stop_rc
expect_eq "repeat exit status after SIGTERM" "$rc" 0

echo "  $samples samples, $frames frames, flashes starting at (1/100 s):$starts"
states=$(sed -n 's/.*"state":"\([A-Z]*\)".*/\1/p' /tmp/blink.out | sort -u | tr '\n' ' ')
expect_eq "states shown" "$states" "LOST "
if [ "$frames" -ge 8 ] && [ "$frames" -le 20 ]; then ok "about 2 fps ($frames frames in 7 s)"; else
  bad "$frames frames in 7 s; vivid was asked for 2 fps"
fi
if [ "$flashes" -ge 2 ]; then ok "$flashes LOST flashes in 7 s"; else bad "$flashes LOST flashes in 7 s, expected 3 (one every 2 s)"; fi
# 100 ms on; a sample every few ms, so a flash reads 0.1 s give or take the sampling. A
# flash held until the next frame reads 0.5 s.
if [ "$flashes" -ge 1 ] && [ "$longest" -le 30 ]; then ok "the longest flash lasted $longest/100 s (100 ms expected)"; else
  bad "the longest flash lasted $longest/100 s; a 100 ms flash was expected, not one held until the next frame"
fi
prev=
for s in $starts; do
  if [ -n "$prev" ]; then
    gap=$((s - prev))
    if [ "$gap" -ge 190 ] && [ "$gap" -le 210 ]; then ok "flashes $gap/100 s apart"; else bad "flashes $gap/100 s apart, expected 2 s"; fi
  fi
  prev=$s
done
sed 's/^/       | /' /tmp/blink.err | tail -n 4
finish_scenario
