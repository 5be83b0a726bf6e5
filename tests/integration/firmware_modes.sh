#!/usr/bin/env bash
# Whole-command tests of the firmware modes, run as a user runs them:
#   firmware_modes.sh SKYLOC SMALL_CONFIG [EMULATOR...]
# teach/repeat on the simulated camera, refusals with clear errors, SIGTERM (clean
# shutdown, route committed), SIGUSR1 (latency table), kill -9 during teach + recovery.
set -u
SKYLOC=$1
CONFIG=$2
shift 2
RUN=("$@" "$SKYLOC")
# A program that is not there (a build that stopped before it) fails here, at once: each
# wait below would otherwise run out, and CTest's timeout kills the script with SIGKILL,
# which leaves its scratch folder in /tmp.
if [ ! -x "$SKYLOC" ]; then
  echo "FAIL: $SKYLOC is not an executable program: build the skyloc target first" >&2
  exit 1
fi
WORK=$(mktemp -d /tmp/skyloc_modes_XXXXXX)
trap 'rm -rf "$WORK"' EXIT
failures=0
fail() {
  echo "FAIL: $*" >&2
  failures=$((failures + 1))
}
expect_rc() {  # expect_rc WANT DESCRIPTION -- command...
  local want=$1 what=$2
  shift 3
  "$@" >"$WORK/out" 2>"$WORK/err"
  local rc=$?
  [ "$rc" -eq "$want" ] || fail "$what: exit $rc, expected $want; stderr: $(cat "$WORK/err")"
}
# The JSON lines of frames (the stream also carries a devices record once a second).
frame_lines() {
  grep -c '^{"schema":1,"frame":' "$1"
}
# Waits (at most 60 s) until FILE holds a frame's JSON line: the program is in its loop, its
# signal handlers installed. A fixed sleep raced a slow start (a loaded machine, a sanitizer,
# qemu-user): a signal sent before the handlers are in kills with the default action.
wait_for_frames() {  # wait_for_frames FILE
  for _ in $(seq 600); do
    grep -q '^{"schema":1,"frame":' "$1" 2>/dev/null && return 0
    sleep 0.1
  done
  fail "no frame line in $1 within 60 s"
}
expect_err() {  # expect_err PATTERN DESCRIPTION
  grep -q -- "$1" "$WORK/err" || fail "$2: stderr lacks '$1': $(cat "$WORK/err")"
}

DB=$WORK/route.db
# 1. teach a bounded run, then inspect it.
expect_rc 0 "teach" -- "${RUN[@]}" teach --route "$DB" --config "$CONFIG" --frames 150
[ "$(frame_lines "$WORK/out")" -eq 150 ] || fail "teach printed $(frame_lines "$WORK/out") JSON lines, expected 150"
grep -q '^{"devices":{"timestamp":' "$WORK/out" || fail "teach: no devices record in the JSON lines"
grep -q '"route_frames":150' "$WORK/out" || fail "teach JSON lacks route_frames 150"
expect_err "150 frames committed" "teach summary"
# one start-up line names the camera, the status output and the route; a simulated camera
# in a live mode is a loud warning
expect_err "skyloc teach: camera sim (SIMULATED world \"street\", seed 1), GREY 96x96 @ 200 fps; status sim (SIMULATED, no GPIO line); route $DB (new); config $CONFIG" "start-up line"
expect_err "WARNING: the camera is SIMULATED" "teach on the simulated camera"
expect_rc 0 "route info" -- "${RUN[@]}" route info "$DB"
grep -q "150 frames in 15 chunks, committed" "$WORK/out" || fail "route info: $(cat "$WORK/out")"
grep -q "lens equidistant 96x96, fov 185.00 degrees, centre 47.50 47.50 px, radius 48.00 px" "$WORK/out" ||
  fail "route info lacks the lens: $(cat "$WORK/out")"
# the strip's encoding (format 6): 360 columns at 4 bits, a byte minimum and a byte range
grep -q "format version 6," "$WORK/out" || fail "route info: not format 6: $(cat "$WORK/out")"
grep -q "horizon strips for heading: 360 columns at 4 bits a column (182 bytes per frame)" "$WORK/out" ||
  fail "route info lacks the strip's encoding: $(cat "$WORK/out")"

# 2. a taught route is never replaced silently.
expect_rc 1 "teach over an existing route" -- "${RUN[@]}" teach --route "$DB" --config "$CONFIG" --frames 5
expect_err "already exists: not replacing a taught route; pass --force to replace it" "teach over an existing route"

# 3. repeat the same street: one JSON line per frame with every key; it localises.
expect_rc 0 "repeat" -- "${RUN[@]}" repeat --route "$DB" --config "$CONFIG" --frames 150
[ "$(frame_lines "$WORK/out")" -eq 150 ] || fail "repeat printed $(frame_lines "$WORK/out") lines"
for key in frame timestamp best_index uniqueness confidence state heading_deg heading_confidence \
  heading_surf_deg heading_surf_inliers latency_us; do
  [ "$(grep '^{"schema":1,"frame":' "$WORK/out" | grep -c "\"$key\":")" -eq 150 ] || fail "repeat: key $key missing on some lines"
done
grep -q '"state":"LOCALISED"' "$WORK/out" || fail "repeat never localised"
# The same street, the same way round: matched frames carry a heading near 0.
grep -q '"heading_deg":-\?[0-9]\.' "$WORK/out" || fail "repeat: no matched frame has a heading"
expect_err "p99_us" "repeat latency table at exit"
expect_err "precision at 100% recall" "repeat evaluation"
expect_err "route $DB (150 frames)" "repeat start-up line"
expect_err "WARNING: the status output is SIMULATED" "repeat with the simulated status output"
# A route without horizon strips (taught with [heading] strip_columns = 0, as every file
# before format 4) still localises with heading on: heading null, one note at start-up.
{ cat "$CONFIG"; printf '\n[heading]\nstrip_columns = 0\n'; } >"$WORK/nostrips.toml"
expect_rc 0 "teach without strips" -- "${RUN[@]}" teach --route "$WORK/nostrips.db" --config "$WORK/nostrips.toml" --frames 60
expect_rc 0 "repeat a route without strips" -- "${RUN[@]}" repeat --route "$WORK/nostrips.db" --config "$CONFIG" --frames 40
expect_err "strip_columns = 0: heading is off; re-teach to get heading" "repeat a route without strips"
[ "$(grep -c 'heading is off' "$WORK/err")" -eq 1 ] || fail "the no-strips note is not said exactly once"
[ "$(grep -c '"heading_deg":null' "$WORK/out")" -eq 40 ] || fail "a route without strips gave a heading"
grep -q '"best_index":[0-9]' "$WORK/out" || fail "a route without strips did not match"

# 4. settings that differ from the taught ones are refused, naming the setting.
sed 's/^bands = 24/bands = 16/' "$CONFIG" >"$WORK/other.toml"
expect_rc 1 "repeat with other bands" -- "${RUN[@]}" repeat --route "$DB" --config "$WORK/other.toml" --frames 5
expect_err "taught with \\[descriptor\\] bands = 24 but this configuration has 16: set \\[descriptor\\] bands = 24 or teach again" "settings mismatch"
# A route taught with the old default (64 bands) is refused by the new default by name, with
# the setting that repeats it; with that setting it loads.
sed 's/^bands = 24/bands = 64/' "$CONFIG" >"$WORK/bands64.toml"
sed '/^bands = 24/d' "$CONFIG" >"$WORK/default_bands.toml"
expect_rc 0 "teach with the old default bands" -- "${RUN[@]}" teach --route "$WORK/bands64.db" --config "$WORK/bands64.toml" --frames 5
expect_rc 1 "repeat a 64-band route with the default bands" -- "${RUN[@]}" repeat --route "$WORK/bands64.db" --config "$WORK/default_bands.toml" --frames 5
expect_err "route database $WORK/bands64.db: taught with \\[descriptor\\] bands = 64 but this configuration has 120: set \\[descriptor\\] bands = 64 or teach again" "old default bands refused"
expect_rc 0 "repeat a 64-band route with bands = 64" -- "${RUN[@]}" repeat --route "$WORK/bands64.db" --config "$WORK/bands64.toml" --frames 5
# the default lens written out to a camera file is the same lens; another one is named
write_lens() {  # write_lens FILE FOV CENTRE_X
  printf '[image]\nwidth = 96\nheight = 96\n[lens]\nmodel = "equidistant"\nfov_deg = %s\ncentre = [%s, 47.5]\nradius_px = 48.0\n' "$2" "$3" >"$1"
}
write_lens "$WORK/same_lens.toml" 185.0 47.5
write_lens "$WORK/other_lens.toml" 180.0 47.5
sed "s|^height = 96|height = 96\nlens_file = \"$WORK/same_lens.toml\"|" "$CONFIG" >"$WORK/same.toml"
sed "s|^height = 96|height = 96\nlens_file = \"$WORK/other_lens.toml\"|" "$CONFIG" >"$WORK/other.toml"
expect_rc 0 "repeat with the default lens from a camera file" -- "${RUN[@]}" repeat --route "$DB" --config "$WORK/same.toml" --frames 5
expect_rc 1 "repeat with another lens" -- "${RUN[@]}" repeat --route "$DB" --config "$WORK/other.toml" --frames 5
expect_err "route database $DB: lens differs (taught vs now): fov 185.00 vs 180.00 degrees: use the camera file it was taught with, or teach again" "lens mismatch"

# 5. a bad configuration value: one error naming file:line and key.
printf '[seqslam]\nds = 0\n' >"$WORK/bad.toml"
expect_rc 1 "bad config" -- "${RUN[@]}" repeat --route "$DB" --config "$WORK/bad.toml"
expect_err "bad.toml:2: \[seqslam\] ds" "bad config"
expect_rc 2 "missing --route" -- "${RUN[@]}" repeat --config "$CONFIG"
expect_err "skyloc repeat: --route FILE.db is required" "missing --route"
expect_rc 2 "tilt out of range" -- "${RUN[@]}" teach --route "$WORK/t.db" --tilt 95
expect_err "skyloc teach: --tilt '95': expected a number in \[-90, 90\]" "tilt out of range"
[ ! -e "$WORK/t.db" ] || fail "a refused teach command line created its route database"
expect_rc 2 "frames not a count" -- "${RUN[@]}" record "$WORK/rec" --frames x
expect_err "skyloc record: --frames 'x': expected a whole number >= 0" "frames not a count"
expect_rc 2 "replay --pace" -- "${RUN[@]}" replay "$WORK" --route "$DB" --pace slow
expect_err "skyloc replay: --pace 'slow': expected recorded or fast" "replay --pace"
expect_rc 0 "route info --help" -- "${RUN[@]}" route info --help
grep -q "^usage: skyloc route info FILE.db | recover \[--salvage\] FILE.db" "$WORK/out" ||
  fail "route info --help did not print route's help: $(cat "$WORK/out")"
expect_rc 2 "route bogus" -- "${RUN[@]}" route bogus "$DB"
expect_err "skyloc route: unknown route subcommand 'bogus': expected info or recover" "route bogus"
expect_rc 2 "route info --salvage" -- "${RUN[@]}" route info --salvage "$DB"
expect_err "skyloc route: --salvage is for 'route recover' only" "route info --salvage"
expect_rc 1 "--config DIR" -- "${RUN[@]}" teach --route "$WORK/dir.db" --config "$WORK" --frames 5
expect_err "config $WORK is a directory" "--config DIR"

# 6. SIGTERM during an endless teach: exit 0, every frame so far committed.
"${RUN[@]}" teach --route "$WORK/term.db" --config "$CONFIG" >"$WORK/term.out" 2>"$WORK/term.err" &
pid=$!
wait_for_frames "$WORK/term.out"
sleep 1
kill -TERM $pid
wait $pid
rc=$?
[ $rc -eq 0 ] || fail "teach after SIGTERM exited $rc: $(cat "$WORK/term.err")"
grep -q "stopped by signal" "$WORK/term.err" || fail "teach did not report the signal"
"${RUN[@]}" route info "$WORK/term.db" >"$WORK/out" 2>&1 || fail "route info after SIGTERM: $(cat "$WORK/out")"
grep -q "committed" "$WORK/out" && ! grep -q "NOT committed" "$WORK/out" || fail "SIGTERM teach not committed: $(cat "$WORK/out")"
lines=$(frame_lines "$WORK/term.out")
grep -q "$lines frames in" "$WORK/out" || fail "SIGTERM teach printed $lines lines but $(cat "$WORK/out")"

# 7. SIGUSR1 prints the latency table and the run goes on.
"${RUN[@]}" repeat --route "$DB" --config "$CONFIG" >"$WORK/usr1.out" 2>"$WORK/usr1.err" &
pid=$!
wait_for_frames "$WORK/usr1.out"
kill -USR1 $pid
sleep 0.5
kill -0 $pid 2>/dev/null || fail "repeat died on SIGUSR1"
kill -TERM $pid
wait $pid || fail "repeat after SIGTERM exited non-zero"
[ "$(grep -c p99_us "$WORK/usr1.err")" -ge 2 ] || fail "SIGUSR1 table missing: $(cat "$WORK/usr1.err")"
# The device counters' table follows the latency table, on SIGUSR1 and at exit.
[ "$(grep -c '^camera ' "$WORK/usr1.err")" -ge 2 ] || fail "SIGUSR1 device table missing: $(cat "$WORK/usr1.err")"
grep -q "latency after [0-9]* frames (SIGUSR1" "$WORK/usr1.err" || fail "SIGUSR1 table has no label: $(cat "$WORK/usr1.err")"

# 8. kill -9 during teach: the file is refused as interrupted, recovered, then usable.
"${RUN[@]}" teach --route "$WORK/kill.db" --config "$CONFIG" >"$WORK/kill.out" 2>&1 &
pid=$!
wait_for_frames "$WORK/kill.out"
sleep 1
kill -KILL $pid
wait $pid 2>/dev/null
expect_rc 1 "repeat on an interrupted route" -- "${RUN[@]}" repeat --route "$WORK/kill.db" --config "$CONFIG" --frames 5
expect_err "no commit record" "interrupted route"
expect_err "skyloc route recover" "interrupted route"
expect_rc 0 "route recover" -- "${RUN[@]}" route recover "$WORK/kill.db"
grep -q "recovered" "$WORK/out" || fail "route recover: $(cat "$WORK/out")"
expect_rc 0 "repeat on the recovered route" -- "${RUN[@]}" repeat --route "$WORK/kill.db" --config "$CONFIG" --frames 20

# 9. replay: teach from one simulated recording, replay another (other jitter, tilt, dawn).
# A build with the lab's tools makes them with `skyloc simulate` (poses: replay scores
# itself); the firmware-only build (ARM) records its own simulated camera (no poses).
if "${RUN[@]}" --help | grep -q "^  simulate "; then
  make_dataset() { # DIR FRAMES WIDTH HEIGHT [simulate flags...]
    local dir=$1 frames=$2 w=$3 h=$4
    shift 4
    "${RUN[@]}" simulate --world city --spacing 1 --out "$dir" --frames "$frames" --width "$w" --height "$h" "$@" >/dev/null 2>&1
  }
  with_poses=1
else
  make_dataset() {
    local dir=$1 frames=$2 w=$3 h=$4
    shift 4
    printf '[camera]\nkind = "sim"\nsim_world = "city"\nwidth = %d\nheight = %d\nfps = 200.0\n[descriptor]\nbands = 24\n' "$w" "$h" >"$WORK/record_$w.toml"
    "${RUN[@]}" record "$dir" --config "$WORK/record_$w.toml" --frames "$frames" "$@" >/dev/null 2>&1
  }
  with_poses=0
fi
if make_dataset "$WORK/ref" 60 96 96 && make_dataset "$WORK/qry" 60 96 96 --run 2 --tilt 5 --lighting dawn; then
  expect_rc 0 "teach from a dataset" -- "${RUN[@]}" teach --route "$WORK/ds.db" --config "$CONFIG" --dataset "$WORK/ref"
  expect_err "60 frames committed" "teach from a dataset"
  expect_rc 0 "replay" -- "${RUN[@]}" replay "$WORK/qry" --route "$WORK/ds.db" --config "$CONFIG" --pace fast
  [ "$(frame_lines "$WORK/out")" -eq 60 ] || fail "replay printed $(frame_lines "$WORK/out") lines"
  if [ "$with_poses" = 1 ]; then expect_err "precision at 100% recall" "replay evaluation"; fi
  expect_rc 1 "replay of a missing dataset" -- "${RUN[@]}" replay "$WORK/nothing" --route "$WORK/ds.db"
  expect_err "nothing" "replay of a missing dataset"
  # a frame of another size in a recording: a data-loss error naming the file, exit 1
  # (teach and replay), not a silently skipped frame.
  cp -r "$WORK/qry" "$WORK/odd"
  if make_dataset "$WORK/small" 2 64 64; then
    odd=$(sed -n '12p' "$WORK/odd/frames.csv" | cut -d, -f2)
    cp "$WORK/small/frames/$(sed -n '2p' "$WORK/small/frames.csv" | cut -d, -f2)" "$WORK/odd/frames/$odd"
    expect_rc 1 "replay with a frame of another size" -- "${RUN[@]}" replay "$WORK/odd" --route "$WORK/ds.db" --config "$CONFIG" --pace fast
    expect_err "$odd) is 64x64 .*, expected 96x96" "replay with a frame of another size"
    expect_rc 1 "teach with a frame of another size" -- "${RUN[@]}" teach --route "$WORK/odd.db" --config "$CONFIG" --dataset "$WORK/odd"
    expect_err "$odd) is 64x64 .*, expected 96x96" "teach with a frame of another size"
  else
    fail "could not write the 64x64 dataset"
  fi
else
  fail "could not write the replay datasets"
fi

# 10a. a start-up failure after the configuration (here: no such GPIO chip, or no libgpiod
# in this build) is one error naming [status], and teach leaves no route file behind.
cp "$CONFIG" "$WORK/gpio.toml"
printf '[status]\nkind = "gpio"\nchip = "gpiochip99"\n' >>"$WORK/gpio.toml"
expect_rc 1 "teach with a missing GPIO chip" -- "${RUN[@]}" teach --route "$WORK/gpio.db" --config "$WORK/gpio.toml" --frames 5
expect_err "gpio" "teach with a missing GPIO chip"
[ ! -e "$WORK/gpio.db" ] || fail "a failed start-up left $WORK/gpio.db behind"

# 10. teach stops when the route is full.
sed 's/^route_frames = 5000/route_frames = 50/' "$CONFIG" >"$WORK/cap.toml"
expect_rc 0 "teach up to the capacity" -- "${RUN[@]}" teach --route "$WORK/full.db" --config "$WORK/cap.toml" --frames 60
expect_err "the route is full" "teach capacity"
expect_err "50 frames committed" "teach capacity"

# 11. disk full during teach (RLIMIT_FSIZE: 20 KiB): the chunk that does not fit is lost,
# the frames before it are committed and said so; the route loads strictly. Format 6 with
# small.toml: 240-byte header, chunks of 10 records of 34 + 2 x 24 + 182 (the strip: 2 +
# 360 / 2) = 264 bytes: 240 + 7 x 2672 fits in 20480 bytes, an eighth chunk does not.
(ulimit -f 20 && exec "${RUN[@]}" teach --route "$WORK/fsize.db" --config "$CONFIG" --frames 300) \
  >/dev/null 2>"$WORK/err"
rc=$?
[ $rc -eq 1 ] || fail "teach on a full disk exited $rc, expected 1: $(cat "$WORK/err")"
expect_err "70 frames kept and committed; the last 10 did not fit" "teach on a full disk"
# The run's closing line is written on the error path too: how far the teach got.
grep -Eq "skyloc teach: [0-9]+ frames \([0-9]+ LOST, [0-9]+ SEARCHING, [0-9]+ LOCALISED\)" "$WORK/err" ||
  fail "teach on a full disk ended without its frames line: $(cat "$WORK/err")"
expect_rc 0 "route info after a full disk" -- "${RUN[@]}" route info "$WORK/fsize.db"
grep -q "70 frames in 7 chunks, committed" "$WORK/out" || fail "full-disk route: $(cat "$WORK/out")"

# Recording: `skyloc record DIR` and `teach --record DIR` write dataset folders that teach
# --dataset reads back. The recorder's writer thread cannot start under qemu-user
# (tests/support/emulator.h), so only the native build runs this part.
if [ ${#RUN[@]} -eq 1 ]; then
  REC=$WORK/recording
  expect_rc 0 "record" -- "${RUN[@]}" record "$REC" --config "$CONFIG" --frames 40
  [ "$(frame_lines "$WORK/out")" -eq 40 ] || fail "record printed $(frame_lines "$WORK/out") JSON lines, expected 40"
  expect_err "recording into $REC" "record start-up line"
  # The writer may fall behind the 200 fps camera on a loaded machine and drop frames
  # (counted, and tested exactly in frame_recorder_test); every frame is one or the other,
  # and frames.csv holds exactly the written ones.
  written=$(sed -nE "s|.*recording $REC: ([0-9]+) frames written, ([0-9]+) dropped.*|\1|p" "$WORK/err")
  dropped=$(sed -nE "s|.*recording $REC: ([0-9]+) frames written, ([0-9]+) dropped.*|\2|p" "$WORK/err")
  if [ -z "$written" ] || [ $((written + dropped)) -ne 40 ] || [ "$written" -lt 1 ]; then
    fail "record summary: expected N written and M dropped with N + M = 40: $(cat "$WORK/err")"
  else
    [ "$(wc -l <"$REC/frames.csv")" -eq $((written + 1)) ] ||
      fail "record: frames.csv has $(wc -l <"$REC/frames.csv") lines for $written frames written"
  fi
  grep -q '^model = "equidistant"' "$REC/camera.toml" || fail "record: no camera.toml with the lens"
  expect_rc 1 "record into an earlier recording" -- "${RUN[@]}" record "$REC" --config "$CONFIG" --frames 5
  expect_err "already exists: choose a new folder" "record into an earlier recording"
  expect_rc 2 "record without a folder" -- "${RUN[@]}" record --config "$CONFIG"
  # teach --record into an earlier recording is refused before the route file is made.
  expect_rc 1 "teach --record into an earlier recording" -- "${RUN[@]}" teach \
    --route "$WORK/refused.db" --config "$CONFIG" --frames 5 --record "$REC"
  expect_err "already exists: choose a new folder" "teach --record into an earlier recording"
  [ ! -e "$WORK/refused.db" ] || fail "a refused teach --record left $WORK/refused.db behind"
  expect_rc 0 "teach --record" -- "${RUN[@]}" teach --route "$WORK/recorded.db" --config "$CONFIG" \
    --frames 30 --record "$WORK/taught_run"
  taught=$(sed -nE "s|.*recording $WORK/taught_run: ([0-9]+) frames written.*|\1|p" "$WORK/err")
  if [ -z "$taught" ] || [ "$taught" -lt 1 ] || [ "$taught" -gt 30 ]; then
    fail "teach --record summary: no 'N frames written' (1..30): $(cat "$WORK/err")"
  fi
  expect_rc 0 "teach from the recording" -- "${RUN[@]}" teach --route "$WORK/again.db" \
    --config "$CONFIG" --dataset "$WORK/taught_run"
  expect_err "${taught:-30} frames committed" "teach from the recording"
  # That route has no poses (the recording has none): repeat on the simulated camera has
  # poses for its frames, but none to check a match against; it says so instead of
  # scoring every match wrong.
  expect_rc 0 "repeat on a route without poses" -- "${RUN[@]}" repeat --route "$WORK/again.db" \
    --config "$CONFIG" --frames 40
  ! grep -q "precision at 100% recall" "$WORK/err" ||
    fail "repeat on a route without poses printed a precision: $(grep precision "$WORK/err")"
  expect_err "no precision/recall: route $WORK/again.db has no poses" "repeat on a route without poses"
fi

if [ $failures -ne 0 ]; then
  echo "$failures check(s) failed" >&2
  exit 1
fi
echo "firmware modes: all checks passed"
