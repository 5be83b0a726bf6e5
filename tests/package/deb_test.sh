#!/usr/bin/env bash
# package.deb_host: packs BINARY with packaging/make-deb.sh, runs lintian on the .deb,
# then installs it with apt into a fresh Debian root of this machine's suite (mmdebstrap
# --variant=apt, from the same archive) and checks there, in mmdebstrap's customize hook
# (in_root_checks.sh), that skyloc runs from /usr/bin, the user and the directories
# exist, remove keeps /var/lib/skyloc and purge removes /etc/skyloc. Everything happens
# in WORK_DIR, which is removed at the end (mmdebstrap's root too): nothing in /tmp.
#
#   tests/package/deb_test.sh BINARY WORK_DIR
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
binary=$1 work=$2
fail() {
  echo "package.deb_host: FAILED: $*" >&2
  exit 1
}
rm -rf "$work"
mkdir -p "$work"
trap 'rm -rf "$work"' EXIT
start=$SECONDS

arch=$(dpkg --print-architecture)
deb=$("$ROOT/packaging/make-deb.sh" "$binary" "$arch" "$work") || fail "packaging/make-deb.sh"
echo "built $deb ($(stat -c %s "$deb") bytes) in $((SECONDS - start)) s"
dpkg-deb -f "$deb" Depends

t=$SECONDS
# lintian leaves its mldbm-elf-* databases in TMPDIR: keep them in WORK_DIR.
mkdir -p "$work/tmp"
TMPDIR="$work/tmp" lintian --fail-on error,warning --info "$deb" || fail "lintian rejects $deb"
echo "lintian: clean in $((SECONDS - t)) s"

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
echo "package.deb_host: PASSED in $((SECONDS - start)) s"
