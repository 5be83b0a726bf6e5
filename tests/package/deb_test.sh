#!/usr/bin/env bash
# The package tests: packs BINARY with packaging/make-deb.sh, runs lintian on the .deb,
# installs it with apt into a Debian root and checks there (in_root_checks.sh) that skyloc
# runs from /usr/bin, the user and the directories exist, remove keeps /var/lib/skyloc and
# purge removes /etc/skyloc.
#
#   tests/package/deb_test.sh BINARY WORK_DIR                  # package.deb_host
#   tests/package/deb_test.sh BINARY WORK_DIR arm64 SYSROOT    # package.deb_arm64
#
# This machine's architecture: a fresh root of its suite (mmdebstrap --variant=apt, from
# the same archive), the checks in mmdebstrap's customize hook. arm64: the cached arm64
# root (tests/package/arm64_root.sh, CTest fixture package.arm64_root) booted in the arm64
# HIL VM with the .deb and the checks (tests/hil/run.sh --snapshot-disk, scenario
# deb_install): its dpkg and maintainer scripts are arm64 programs, which this machine
# cannot run. Everything happens in WORK_DIR, which is removed at the end: nothing in /tmp.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
binary=$1 work=$2
host_arch=$(dpkg --print-architecture)
arch=${3:-$host_arch} sysroot=${4:-}
test_name=package.deb_host
[ "$arch" = "$host_arch" ] || test_name=package.deb_$arch
fail() {
  echo "$test_name: FAILED: $*" >&2
  exit 1
}
rm -rf "$work"
mkdir -p "$work"
trap 'rm -rf "$work"' EXIT
start=$SECONDS

deb=$("$ROOT/packaging/make-deb.sh" "$binary" "$arch" "$work" ${sysroot:+"$sysroot"}) || fail "packaging/make-deb.sh"
echo "built $deb ($(stat -c %s "$deb") bytes) in $((SECONDS - start)) s"
dpkg-deb -f "$deb" Depends

t=$SECONDS
# lintian leaves its mldbm-elf-* databases in TMPDIR: keep them in WORK_DIR.
mkdir -p "$work/tmp"
TMPDIR="$work/tmp" lintian --fail-on error,warning --info "$deb" || fail "lintian rejects $deb"
echo "lintian: clean in $((SECONDS - t)) s"

if [ "$arch" != "$host_arch" ]; then
  [ "$arch" = arm64 ] || fail "no Debian root to install a $arch package into (only $host_arch and arm64)"
  cache=${SKYLOC_HIL_CACHE:-$ROOT/build/hil-cache}
  image=$cache/debian-root-arm64/root.img
  [ -f "$image" ] || fail "no arm64 Debian root at $image: tests/package/arm64_root.sh makes it (CTest: package.arm64_root)"
  t=$SECONDS
  rc=0
  # --snapshot-disk: the guest's writes go to QEMU's temporary overlay (in run.sh's work
  # folder, here inside WORK_DIR), so the cached root stays as it was made.
  TMPDIR="$work" "$ROOT/tests/hil/run.sh" --arch arm64 --tests deb_install --name "$test_name" \
    --log "$work.log" --cache "$cache" --snapshot-disk "$image" --file "$deb" \
    --file "$ROOT/tests/package/in_root_checks.sh" --timeout 600 --scenario-timeout 540 || rc=$?
  [ "$rc" -ne 77 ] || exit 77
  [ "$rc" -eq 0 ] || fail "installing $deb in the arm64 root in the VM (console: $work.log)"
  echo "installed, ran, removed and purged in the arm64 root in the VM in $((SECONDS - t)) s"
  echo "$test_name: PASSED in $((SECONDS - start)) s"
  exit 0
fi

t=$SECONDS
suite=$("$ROOT/toolchains/debian-sources.sh" --suite)
mapfile -t sources < <("$ROOT/toolchains/debian-sources.sh")
# The .deb goes in as on the robot: apt install ./skyloc_*.deb, which fetches its
# Depends from the archive. systemd-standalone-sysusers rather than systemd provides
# postinst's systemd-sysusers: the root has no init system, and it is much smaller.
# shellcheck disable=SC2016 # the hooks' $1 is mmdebstrap's, expanded by its shell
if ! TMPDIR="$work" mmdebstrap --variant=apt --include=systemd-standalone-sysusers \
  --customize-hook="copy-in $deb /root" \
  --customize-hook='chroot "$1" env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends ./root/'"$(basename "$deb")" \
  --customize-hook="$ROOT/tests/package/in_root_checks.sh" \
  "$suite" /dev/null "${sources[@]}" >"$work/mmdebstrap.log" 2>&1; then
  grep -vE "^(Get|Preparing|Unpacking|Selecting|Setting up|Processing)" "$work/mmdebstrap.log" | tail -40 >&2
  fail "installing $deb in a Debian $suite root (above)"
fi
grep "^in-root:" "$work/mmdebstrap.log"
echo "installed, ran, removed and purged in a $suite root in $((SECONDS - t)) s"
echo "$test_name: PASSED in $((SECONDS - start)) s"
