#!/usr/bin/env bash
# A taught route is never lost, with real processes racing on one route:
#   teach_races.sh SKYLOC SMALL_CONFIG ROUNDS [EMULATOR...]
# Once: a stale FILE.db.tmp (a `teach --force` killed with SIGKILL) is reported by
# `route info` and by the next teach, which says it replaces it. Then ROUNDS times each:
#   1. a second `teach --force` while one runs: refused, and the running one commits whole;
#   2. a `teach --force` that commits nothing (a full disk before its first chunk; SIGINT
#      as soon as it started): the old route stays;
#   3. `teach --force --frames 3` while a plain teach runs: refused, the plain teach's
#      frames are what the file holds.
# After every race the route must load (`route info`: committed) with the frames the last
# successful commit announced. Prints "races: R rounds, N checks, F failures".
set -u
SKYLOC=$1
CONFIG=$2
ROUNDS=$3
shift 3
RUN=("$@" "$SKYLOC")
# A program that is not there (a build that stopped before it) fails here, at once: each
# wait below would otherwise run out, and CTest's timeout kills the script with SIGKILL,
# which leaves its scratch folder in /tmp.
if [ ! -x "$SKYLOC" ]; then
  echo "FAIL: $SKYLOC is not an executable program: build the skyloc target first" >&2
  exit 1
fi
WORK=$(mktemp -d /tmp/skyloc_races_XXXXXX)
pids=()
cleanup() {
  local p
  for p in "${pids[@]}"; do kill -KILL "$p" 2>/dev/null; done
  rm -rf "$WORK"
}
trap cleanup EXIT
DB=$WORK/route.db
failures=0
checks=0
fail() {
  echo "FAIL: $*" >&2
  failures=$((failures + 1))
}
check() {  # check DESCRIPTION -- command...: counts one check, fails when the command does
  local what=$1
  shift 2
  checks=$((checks + 1))
  "$@" || fail "$what"
}
# Waits (up to 60 s: a loaded machine, a sanitizer or qemu-user starts a teach slowly) until
# FILE exists and is larger than BYTES.
wait_for_size() {
  local file=$1 bytes=$2 i
  for ((i = 0; i < 3000; i++)); do
    if [ -f "$file" ] && [ "$(stat -c %s "$file")" -gt "$bytes" ]; then return 0; fi
    sleep 0.02
  done
  return 1
}
# The frames `route info` says FILE holds, committed; empty when it does not load.
committed_frames() {
  "${RUN[@]}" route info "$1" 2>/dev/null | sed -nE 's/^.*: ([0-9]+) frames in [0-9]+ chunks, committed;.*/\1/p'
}
# The frames a teach's stderr says it committed; empty when it committed none.
said_committed() {
  sed -nE 's/^skyloc teach: route .*: ([0-9]+) frames committed$/\1/p' "$1"
}
# A committed route of N frames at DB, whatever was there.
fresh_route() {
  rm -f "$DB" "$DB.tmp"
  "${RUN[@]}" teach --route "$DB" --config "$CONFIG" --frames "$1" >/dev/null 2>"$WORK/fresh.err" ||
    fail "could not teach the starting route: $(cat "$WORK/fresh.err")"
}
# Both counts known and equal.
same_count() { [ -n "$1" ] && [ "$1" = "$2" ]; }
HEADER=240  # format 4's header, lens and strip records: a larger file holds a chunk

# --- A stale FILE.db.tmp is reported, never replaced silently.
fresh_route 30
"${RUN[@]}" teach --force --route "$DB" --config "$CONFIG" >/dev/null 2>&1 &
pid=$!
pids+=("$pid")
wait_for_size "$DB.tmp" "$HEADER" || fail "the --force teach wrote no chunk to $DB.tmp"
kill -KILL "$pid"
wait "$pid" 2>/dev/null
"${RUN[@]}" route info "$DB" >"$WORK/info.out" 2>&1
check "route info does not mention the stale $DB.tmp: $(cat "$WORK/info.out")" -- \
  grep -q "$DB.tmp: left by an interrupted teach" "$WORK/info.out"
"${RUN[@]}" teach --force --route "$DB" --config "$CONFIG" --frames 20 >/dev/null 2>"$WORK/stale.err"
check "the next teach does not say it replaces the stale $DB.tmp: $(cat "$WORK/stale.err")" -- \
  grep -q "replacing $DB.tmp, left by an interrupted teach" "$WORK/stale.err"
check "after replacing the stale .tmp the route does not hold 20 frames" -- \
  [ "$(committed_frames "$DB")" = 20 ]

start=$SECONDS
for ((round = 1; round <= ROUNDS; round++)); do
  # --- 1. a second teach --force while one runs.
  fresh_route 30
  "${RUN[@]}" teach --force --route "$DB" --config "$CONFIG" >/dev/null 2>"$WORK/a.err" &
  pid=$!
  pids+=("$pid")
  wait_for_size "$DB.tmp" "$HEADER" || fail "race 1 round $round: the first teach wrote no chunk"
  "${RUN[@]}" teach --force --route "$DB" --config "$CONFIG" --frames 3 >/dev/null 2>"$WORK/b.err"
  rc=$?
  check "race 1 round $round: the second teach --force exited $rc: $(cat "$WORK/b.err")" -- [ "$rc" -eq 1 ]
  check "race 1 round $round: the refusal does not say why: $(cat "$WORK/b.err")" -- \
    grep -q "is being taught by process" "$WORK/b.err"
  kill -INT "$pid"
  wait "$pid"
  said=$(said_committed "$WORK/a.err")
  held=$(committed_frames "$DB")
  check "race 1 round $round: the first teach said '${said}' frames committed, the route holds '${held}'" -- \
    same_count "$said" "$held"

  # --- 2. a teach --force that commits nothing: a full disk before the first chunk (2 KiB:
  # the 240-byte header fits, a chunk of 10 frames, 2672 bytes in format 6, does not; stderr is
  # limited too, and its lines fit: about 1.6 KB) ...
  fresh_route 30
  (ulimit -f 2 && exec "${RUN[@]}" teach --force --route "$DB" --config "$CONFIG" --frames 50) \
    >/dev/null 2>"$WORK/full.err"
  rc=$?
  check "race 2 round $round: teach on a full disk exited $rc: $(cat "$WORK/full.err")" -- [ "$rc" -eq 1 ]
  check "race 2 round $round: the full-disk teach does not say the old route is kept: $(cat "$WORK/full.err")" -- \
    grep -q "the old route is kept as it was" "$WORK/full.err"
  check "race 2 round $round: after a full disk the route holds '$(committed_frames "$DB")' frames, not 30" -- \
    [ "$(committed_frames "$DB")" = 30 ]
  # ... and SIGINT as soon as it started (no frame yet, or a few: never an empty route).
  "${RUN[@]}" teach --force --route "$DB" --config "$CONFIG" >/dev/null 2>"$WORK/int.err" &
  pid=$!
  pids+=("$pid")
  wait_for_size "$DB.tmp" 0 || fail "race 2 round $round: the teach never created $DB.tmp"
  kill -INT "$pid"
  wait "$pid"
  said=$(said_committed "$WORK/int.err")
  held=$(committed_frames "$DB")
  if [ -z "$said" ]; then
    check "race 2 round $round: a teach that committed nothing left '${held}' frames, not the old 30" -- \
      [ "$held" = 30 ]
  else
    check "race 2 round $round: the teach said $said frames committed, the route holds '${held}'" -- \
      same_count "$said" "$held"
  fi

  # --- 3. teach --force --frames 3 while a plain teach runs.
  rm -f "$DB" "$DB.tmp"
  "${RUN[@]}" teach --route "$DB" --config "$CONFIG" >/dev/null 2>"$WORK/plain.err" &
  pid=$!
  pids+=("$pid")
  wait_for_size "$DB" "$HEADER" || fail "race 3 round $round: the plain teach wrote no chunk"
  "${RUN[@]}" teach --force --route "$DB" --config "$CONFIG" --frames 3 >/dev/null 2>"$WORK/force.err"
  rc=$?
  check "race 3 round $round: teach --force during a plain teach exited $rc: $(cat "$WORK/force.err")" -- [ "$rc" -eq 1 ]
  kill -INT "$pid"
  wait "$pid"
  said=$(said_committed "$WORK/plain.err")
  held=$(committed_frames "$DB")
  check "race 3 round $round: the plain teach said '${said}' frames committed, the route holds '${held}'" -- \
    same_count "$said" "$held"
  pids=()
done
[ -e "$DB.lock" ] && fail "the route's lock file was left behind"

echo "races: $ROUNDS rounds of 3 races in $((SECONDS - start)) s, $checks checks, $failures failures"
if [ $failures -ne 0 ]; then
  exit 1
fi
echo "teach races: all checks passed"
