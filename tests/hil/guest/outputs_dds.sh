# skyloc's outputs inside the arm64 guest, as outputs.isolated runs them on the build
# machine: the outputs test program (two socket readers, a dead one; a DDS subscriber on
# Cyclone DDS's own API that checks every field of every frame of `skyloc repeat` against
# its JSON line, and /diagnostics). The guest has no network card, and the program runs
# in a network namespace of its own with only the loopback up (busybox unshare and ip),
# which its main() checks before it starts DDS. Nothing may skip here: a build without
# Cyclone DDS would skip the subscriber, which is a failure in this scenario.
# shellcheck source=tests/hil/guest/lib.sh
. /hil/tests/lib.sh

T=/hil/bin/skyloc_outputs_tests
if [ ! -x "$T" ]; then
  bad "$T is not in the image (run.sh --bin)"
  finish_scenario
fi
out=/tmp/outputs.log
echo "--- $T in a network namespace of its own"
# shellcheck disable=SC2016 # "$0" is expanded by the inner shell: the program's path
unshare -n -- sh -c 'ip link set lo up && exec "$0" --gtest_color=no' "$T" >"$out" 2>&1
rc=$?
sed 's/^/    /' "$out"
expect_eq "outputs tests exit status" "$rc" 0
expect_eq "tests skipped" "$(grep -c '^\[  SKIPPED \]' "$out")" 0
if grep -q '^\[       OK \] DdsOutput.ASubscriberSeesEveryFrameOfRepeatAsItsJsonLine ' "$out"; then
  ok "a DDS subscriber saw every frame of repeat as its JSON line"
else
  bad "DdsOutput.ASubscriberSeesEveryFrameOfRepeatAsItsJsonLine did not pass"
fi
if grep -q '^\[       OK \] DdsOutput.HealthGoesToDiagnosticsAsKeyValues ' "$out"; then
  ok "/diagnostics received"
else
  bad "DdsOutput.HealthGoesToDiagnosticsAsKeyValues did not pass"
fi
rm -f "$out"
finish_scenario
