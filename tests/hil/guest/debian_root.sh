# Scenario debian_root: the second stage of the arm64 Debian root (tests/package/arm64_root.sh).
# The disk holds a root mmdebstrap extracted on the build machine (the essential set,
# apt and the package's runtime libraries, their .debs in /var/cache/apt/archives): here,
# on an arm64 kernel, dpkg installs them for real (their maintainer scripts are arm64
# programs, which the build machine cannot run), as mmdebstrap itself does: dpkg
# --install --force-depends of every .deb at once (dpkg does not order Pre-Depends), and
# --force-unsafe-io, as mmdebstrap's own installs: no fsync per unpacked file, since the
# image is only used after the sync and the unmount below (under TCG: dpkg 225 -> 185 s
# of guest time, measured 2026-11-28 on the quiet 2-core machine).
# shellcheck source=tests/hil/guest/lib.sh
. /hil/tests/lib.sh

debian_root_mount || {
  bad "cannot mount the Debian root on /dev/vda (is the disk attached: run.sh --disk?)"
  finish_scenario
}
n=$(find "$DEBIAN_ROOT/var/cache/apt/archives" -maxdepth 1 -name '*.deb' | wc -l)
echo "--- dpkg --install --force-depends: $n packages"
t0=$(cut -d' ' -f1 /proc/uptime)
if in_debian_root sh -c 'dpkg --install --force-depends --force-unsafe-io /var/cache/apt/archives/*.deb' >/tmp/dpkg.log 2>&1; then
  ok "dpkg installed $n packages ($t0 s to $(cut -d' ' -f1 /proc/uptime) s of guest uptime)"
else
  bad "dpkg --install of the extracted packages failed"
  grep -v -e '^Selecting' -e '^Preparing' -e '^Unpacking' -e '^Setting up' /tmp/dpkg.log | tail -n 30 | sed 's/^/       | /'
fi
# Anything left half-configured (a trigger, a package whose dependency came later in
# the list) is configured now; then dpkg must have nothing to complain about.
check "dpkg --configure --pending" in_debian_root dpkg --configure --pending
audit=$(in_debian_root dpkg --audit 2>&1)
expect_eq "dpkg --audit" "${audit:-clean}" clean
# The .debs are not needed any more: the image is cached, smaller is better.
rm -f "$DEBIAN_ROOT"/var/cache/apt/archives/*.deb
sync
check "unmount the Debian root" debian_root_umount
finish_scenario
