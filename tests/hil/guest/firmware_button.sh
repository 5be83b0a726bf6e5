# End to end: teach by button on a real kernel. `skyloc repeat` starts with no route and a
# teach button on gpio-sim line 7 (docs/FIRMWARE.md, "Teach by button"); the button is
# pressed by setting the simulated line's pull, which the kernel turns into edges on the
# line request skyloc holds. Passes when:
#   - with no route, repeat waits: no JSON lines, the status lines safe (000), no route file;
#   - press 1 starts a teach, its frames on the disk as they come;
#   - press 2 commits the route and repeat runs on it (JSON lines, one status line lit);
#   - SIGTERM ends it with status 0, the lines released, and the route loads strictly.
# While this skyloc has no V4L2 camera or GPIO status output, the scenario is SKIPPED
# (pending), never passed.
# shellcheck source=tests/hil/guest/lib.sh
. /hil/tests/lib.sh

SKYLOC=/hil/bin/skyloc
[ -x "$SKYLOC" ] || pending "skyloc is not in this image"

card=$(v4l2-ctl -d "$HIL_VIVID_VIDEO" --info | sed -n 's/^[[:space:]]*Card type *: //p')
CONFIG=/tmp/skyloc_button.toml
ROUTE=/tmp/button_route.db
BUTTON=$HIL_GPIO_SIM_DIR/sim_gpio7
camera_config v4l2 "vivid:$card" 640 400 >"$CONFIG"
status_gpio_config >>"$CONFIG"
cat >>"$CONFIG" <<EOF
button_line = 7
# Pressed reads high: gpio-sim's pull-up is the press, its pull-down the release.
button_active_low = false
button_debounce_ms = 30
EOF

press() { # held for 0.3 s, then released and left released for 0.3 s (debounce: 30 ms)
  echo pull-up >"$BUTTON/pull"
  sleep 0.3
  echo pull-down >"$BUTTON/pull"
  sleep 0.3
}
wait_for() { # wait_for SECONDS PATTERN: until stderr has PATTERN or skyloc exits
  i=0
  while [ "$i" -lt "$(($1 * 10))" ] && kill -0 "$skyloc" 2>/dev/null; do
    grep -q -- "$2" /tmp/button.err && return 0
    sleep 0.1
    i=$((i + 1))
  done
  grep -q -- "$2" /tmp/button.err
}

rm -f "$ROUTE" "$ROUTE.tmp"
echo pull-down >"$BUTTON/pull"
echo "repeat with no route, waiting for the button on line 7"
"$SKYLOC" repeat --route "$ROUTE" --config "$CONFIG" >/tmp/button.out 2>/tmp/button.err &
skyloc=$!
i=0
while [ "$(lines_held_by_skyloc "2,4p;9p")" -lt 4 ] && kill -0 "$skyloc" 2>/dev/null && [ "$i" -lt 300 ]; do
  sleep 0.1
  i=$((i + 1))
done
expect_eq "status lines and button held by consumer skyloc" "$(lines_held_by_skyloc "2,4p;9p")" 4
sleep 1
expect_eq "JSON lines while waiting for the button" "$(json_lines /tmp/button.out)" 0
expect_eq "status lines while waiting (safe)" "$(status_levels)" 000
if [ -e "$ROUTE" ]; then bad "a route file exists before any press"; else ok "no route file before the press"; fi

echo "press 1: teach"
press
if wait_for 20 "teach button pressed"; then
  ok "press 1 started a teach: $(grep -m 1 'teach button pressed' /tmp/button.err)"
else
  bad "no teach after press 1"
  sed 's/^/       | /' /tmp/button.err | tail -n 10
fi
sleep 3
taught=$(json_lines /tmp/button.out)
if [ "$taught" -ge 5 ]; then ok "teaching: $taught frames so far"; else bad "teaching printed $taught JSON lines in 3 s"; fi
# A new route is written in place (it is not loadable until committed); a route that
# exists is replaced only at the commit, from ROUTE.tmp.
into=$(sed -n 's/.*teaching a new route into \([^ ]*\) until.*/\1/p' /tmp/button.err | head -n 1)
if [ -n "$into" ] && [ -s "$into" ]; then ok "frames go to $into"; else bad "no frames on the disk while teaching (into '$into')"; fi

echo "press 2: commit and repeat"
press
if wait_for 30 "repeating on the new route"; then
  ok "$(grep -m 1 'frames committed' /tmp/button.err | sed 's/^skyloc repeat: //')"
else
  bad "no commit and repeat after press 2"
  sed 's/^/       | /' /tmp/button.err | tail -n 10
fi
at_commit=$(json_lines /tmp/button.out)
i=0
while [ "$(json_lines /tmp/button.out)" -lt "$((at_commit + 10))" ] && kill -0 "$skyloc" 2>/dev/null && [ "$i" -lt 300 ]; do
  sleep 0.1
  i=$((i + 1))
done
if [ "$(json_lines /tmp/button.out)" -ge "$((at_commit + 10))" ]; then ok "repeat runs on the taught route"; else
  bad "repeat printed $(($(json_lines /tmp/button.out) - at_commit)) frames in 30 s after the commit"
fi
grep -q '"best_index"' /tmp/button.out || bad "no repeat JSON line (best_index) after the commit"
lit=$(status_levels)
case "$lit" in
  100 | 010 | 001) ok "one status line lit ($lit)" ;;
  *) bad "status lines read $lit while repeating; per-state encoding lights exactly one" ;;
esac

stop_skyloc "$skyloc" /tmp/button.err
rc=$stop_rc
expect_eq "repeat exit status after SIGTERM" "$rc" 0
expect_eq "lines released at exit" "$(lines_held_by_skyloc "2,4p;9p")" 0
if [ -e "$ROUTE.tmp" ]; then bad "$ROUTE.tmp left after the commit"; fi
if "$SKYLOC" route info "$ROUTE" >/tmp/button.info 2>&1 && grep -q "committed" /tmp/button.info; then
  ok "the route loads: $(grep -m 1 'frames in' /tmp/button.info)"
else
  bad "route info: $(cat /tmp/button.info)"
fi
sed 's/^/       | /' /tmp/button.err | tail -n 6
finish_scenario
