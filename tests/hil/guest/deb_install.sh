# Scenario deb_install: the arm64 skyloc .deb (/hil/files/skyloc_*.deb, run.sh --file)
# installed as on the robot, apt install ./skyloc_*.deb (offline: its Depends are in the
# root already), in the arm64 Debian root on the disk (run.sh --snapshot-disk: the cached
# image is not changed); then the same checks as the host package test,
# tests/package/in_root_checks.sh (/hil/files, run.sh --file).
# shellcheck source=tests/hil/guest/lib.sh
. /hil/tests/lib.sh

debian_root_mount || {
  bad "cannot mount the Debian root on /dev/vda (is the disk attached: run.sh --snapshot-disk?)"
  finish_scenario
}
deb=$(find /hil/files -maxdepth 1 -name 'skyloc_*.deb' | head -1)
[ -n "$deb" ] || {
  bad "no skyloc_*.deb in /hil/files (run.sh --file)"
  finish_scenario
}
cp "$deb" "$DEBIAN_ROOT/root/"
name=${deb##*/}
echo "--- apt-get install /root/$name"
if in_debian_root apt-get install -y --no-install-recommends "/root/$name" >/tmp/apt.log 2>&1; then
  ok "apt-get install $name"
else
  bad "apt-get install $name failed (a Depends missing from the root? tests/package/arm64_root.sh lists what it holds)"
  tail -n 30 /tmp/apt.log | sed 's/^/       | /'
  finish_scenario
fi
if sh /hil/files/in_root_checks.sh "$DEBIAN_ROOT"; then
  ok "in_root_checks.sh"
else
  bad "in_root_checks.sh (above)"
fi
debian_root_umount || bad "cannot unmount the Debian root"
finish_scenario
