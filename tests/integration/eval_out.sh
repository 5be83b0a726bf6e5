#!/usr/bin/env bash
# skyloc eval's --out folder: an existing non-empty one is refused unless --force, and a
# full disk (RLIMIT_FSIZE) leaves the previous matches.csv, or none, never a truncated one.
#   eval_out.sh SKYLOC MAKE_EVAL_DATASETS [EMULATOR...]
set -u
SKYLOC=$1
GEN=$2
shift 2
EMU=("$@")
RUN=("${EMU[@]}" "$SKYLOC")
JOBS=()
# Under qemu-user eval runs on one thread (tests/integration/eval_check.cmake says why).
[ ${#EMU[@]} -gt 0 ] && JOBS=(--jobs 1)
WORK=$(mktemp -d /tmp/skyloc_eval_out_XXXXXX)
trap 'rm -rf "$WORK"' EXIT
failures=0
fail() {
  echo "FAIL: $*" >&2
  failures=$((failures + 1))
}
"${EMU[@]}" "$GEN" "$WORK/data" >/dev/null 2>&1 || { echo "FAIL: dataset generator" >&2; exit 1; }
EVAL=(eval --reference "$WORK/data/reference" --query "$WORK/data/query" --method vanilla
      --ds 1 --tolerance-m 1.6 "${JOBS[@]}")

"${RUN[@]}" "${EVAL[@]}" --out "$WORK/out" >/dev/null 2>"$WORK/err" || fail "first eval: $(cat "$WORK/err")"
for f in matches.csv metrics.json pr.svg correspondence.svg; do
  [ -s "$WORK/out/$f" ] || fail "first eval wrote no $f"
done
cp "$WORK/out/matches.csv" "$WORK/matches.before"

# 1. a non-empty --out is refused (a usage error, exit 2) naming the folder and the fix
"${RUN[@]}" "${EVAL[@]}" --out "$WORK/out" >/dev/null 2>"$WORK/err"
rc=$?
[ $rc -eq 2 ] || fail "eval into a non-empty --out exited $rc, expected 2"
grep -q -- "--out $WORK/out is not empty (it holds .*): pass --force to replace its results, or give a new or empty folder" "$WORK/err" ||
  fail "refusal message: $(cat "$WORK/err")"

# 2. --force writes into it
"${RUN[@]}" "${EVAL[@]}" --out "$WORK/out" --force >/dev/null 2>"$WORK/err" || fail "eval --force: $(cat "$WORK/err")"
cmp -s "$WORK/out/matches.csv" "$WORK/matches.before" || fail "eval --force wrote another matches.csv"

# 3. a full disk (1 KiB file size limit; matches.csv is larger): the previous matches.csv
# stays whole, the error names the file and errno's text, no temporary file is left.
[ "$(stat -c %s "$WORK/matches.before")" -gt 1024 ] || fail "matches.csv is too small for the test"
(ulimit -f 1 && exec "${RUN[@]}" "${EVAL[@]}" --out "$WORK/out" --force) >/dev/null 2>"$WORK/err"
rc=$?
[ $rc -eq 1 ] || fail "eval on a full disk exited $rc, expected 1: $(cat "$WORK/err")"
grep -q "cannot write $WORK/out/matches.csv (the previous file, if any, is kept): File too large" "$WORK/err" ||
  fail "full-disk message: $(cat "$WORK/err")"
cmp -s "$WORK/out/matches.csv" "$WORK/matches.before" || fail "a full disk changed the previous matches.csv"
ls -A "$WORK/out" | grep -q tmp && fail "temporary files left: $(ls -A "$WORK/out")"

# 4. the same into a new folder: no matches.csv at all
(ulimit -f 1 && exec "${RUN[@]}" "${EVAL[@]}" --out "$WORK/new") >/dev/null 2>"$WORK/err"
[ -e "$WORK/new/matches.csv" ] && fail "a full disk left a matches.csv: $(wc -c <"$WORK/new/matches.csv") bytes"
[ -z "$(ls -A "$WORK/new")" ] || fail "a full disk left files: $(ls -A "$WORK/new")"

if [ $failures -ne 0 ]; then
  echo "$failures check(s) failed" >&2
  exit 1
fi
echo "all checks passed"
