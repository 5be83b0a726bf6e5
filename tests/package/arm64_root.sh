#!/usr/bin/env bash
# package.arm64_root: makes, once, the arm64 Debian root that package.deb_arm64 installs
# the arm64 .deb into, as an ext4 disk image: CACHE/debian-root-arm64/root.img.
#
#   tests/package/arm64_root.sh [CACHE]     (default: $SKYLOC_HIL_CACHE, else build/hil-cache)
#
# Installing an arm64 package runs arm64 programs (dpkg, the maintainer scripts), and the
# build machines have no binfmt_misc to hand them to qemu-user, so the root is made in two
# stages (docs/PACKAGING.md):
#   1. here, mmdebstrap --variant=extract: the essential set, apt and the package's
#      runtime libraries for arm64, from the archive and suites the sysroots come from
#      (toolchains/debian-sources.sh), extracted into a folder with their .debs kept;
#      mke2fs -d packs it into an ext4 image (no mount needed);
#   2. in the arm64 HIL VM (tests/hil/run.sh --disk, scenario debian_root): dpkg installs
#      every package for real on an arm64 kernel.
# The image is kept until the package list, the suite or ROOT_FORMAT changes (the hash in
# the stamp beside it); the tests boot it with run.sh --snapshot-disk, so it stays as made.
# Exit status: 0 ready; 77 skipped (the HIL VM's set-up was skipped, or not root); else failed.
set -euo pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
CACHE=${1:-${SKYLOC_HIL_CACHE:-$ROOT/build/hil-cache}}
DIR="$CACHE/debian-root-arm64"
SKIP=77
# What the root holds besides the essential set. The package's Depends (make-deb.sh:
# dpkg-shlibdeps, plus postinst's systemd-sysusers) must all be here: the VM has no
# network, so apt installs the .deb offline. usr-is-merged: the root is merged-/usr like
# every Debian 12 system (the setup hook below makes the links), without the usrmerge
# conversion, which init-system-helpers would otherwise pull in.
PACKAGES=(apt usr-is-merged libcamera0.0.3 libgpiod2 libddsc0debian systemd-standalone-sysusers)
# Bump when this script or the debian_root scenario changes what they make.
ROOT_FORMAT=2

say() { printf 'arm64-root: %s\n' "$*" >&2; }
fail() {
  say "FAILED: $*"
  exit 1
}

mkdir -p "$CACHE"
# One maker at a time per cache (two ctest runs of the same build folder, say): the second
# waits, then finds the image made. Not CACHE/lock: setup.sh, called below, takes that one.
exec 8>"$DIR.lock"
flock 8

suite=$("$ROOT/toolchains/debian-sources.sh" --suite)
want=$(printf '%s\n' "format $ROOT_FORMAT" arm64 "$suite" "${PACKAGES[*]}" | sha256sum | cut -d' ' -f1)
if [ -f "$DIR/root.img" ] && [ "$(cat "$DIR/stamp" 2>/dev/null)" = "$want" ]; then
  say "cached: $DIR/root.img ($(wc -l <"$DIR/packages") packages)"
  exit 0
fi
if [ "$(id -u)" -ne 0 ]; then
  say "SKIPPED: making the arm64 Debian root needs root (mmdebstrap and mke2fs keep the files' owners): run the tests as root once"
  exit $SKIP
fi
for tool in mmdebstrap mke2fs; do
  command -v "$tool" >/dev/null || fail "$tool is missing: ./skyloc.sh deps aarch64 installs it"
done
mapfile -t sources < <("$ROOT/toolchains/debian-sources.sh")
[ ${#sources[@]} -gt 0 ] || fail "apt knows no source for Debian '$suite' (apt-get indextargets)"

start=$SECONDS
new="$DIR.new"
rm -rf "$new"
mkdir -p "$new"
trap 'rm -rf "$new"' EXIT
say "stage 1: mmdebstrap --variant=extract, arm64, $suite: essential set + ${PACKAGES[*]}"
# The setup hook makes the merged-/usr links before anything is extracted (debootstrap
# and mmdebstrap's merged-usr hook do the same). The extract hook lists the packages.
# --skip=cleanup/apt/cache keeps the .debs for stage 2.
# shellcheck disable=SC2016 # the hooks' $1 is mmdebstrap's, expanded by its shell
if ! TMPDIR="$new" mmdebstrap --variant=extract --architectures=arm64 --include='?essential' \
  --include="$(
    IFS=,
    echo "${PACKAGES[*]}"
  )" \
  --skip=cleanup/apt/cache \
  --setup-hook='for d in bin sbin lib; do ln -s usr/$d "$1/$d"; mkdir -p "$1/usr/$d"; done' \
  --extract-hook='for d in "$1"/var/cache/apt/archives/*.deb; do dpkg-deb -f "$d" Package Version | paste -sd" "; done | sort >"$1/packages"' \
  "$suite" "$new/root" "${sources[@]}" >"$new/mmdebstrap.log" 2>&1; then
  grep -E "^(E|W|Err):" "$new/mmdebstrap.log" | tail -10 >&2
  fail "mmdebstrap could not extract the arm64 root (above). Is the Debian archive reachable (${sources[*]})?"
fi
mv "$new/root/packages" "$new/packages"
say "stage 1: $(wc -l <"$new/packages") packages extracted in $((SECONDS - start)) s"
# 1 GiB, sparse: the extracted root is ~180 MB and installing writes it once more; the
# package test adds a few MB.
mke2fs -q -t ext4 -L skyloc-arm64 -d "$new/root" "$new/root.img" 1G >"$new/mke2fs.log" 2>&1 ||
  fail "mke2fs -d could not pack $new/root into an ext4 image: $(cat "$new/mke2fs.log")"
rm -rf "$new/root"

t=$SECONDS
# The HIL VM's kernel and initramfs (cached; seconds when warm).
rc=0
"$ROOT/tests/hil/setup.sh" arm64 "$CACHE" || rc=$?
[ "$rc" -eq 0 ] || exit "$rc"
say "stage 2: dpkg --install in the arm64 VM (TCG: minutes); console: $DIR.log"
rc=0
# run.sh's scratch (the initramfs) goes in the new folder too, removed with it.
TMPDIR="$new" "$ROOT/tests/hil/run.sh" --arch arm64 --tests debian_root --name package.arm64_root \
  --log "$DIR.log" --cache "$CACHE" --disk "$new/root.img" --timeout 1800 --scenario-timeout 1700 || rc=$?
[ "$rc" -ne 77 ] || exit 77 # run.sh said why (the VM's set-up was skipped)
[ "$rc" -eq 0 ] || fail "stage 2 (dpkg --install in the arm64 VM) exited $rc: see $DIR.log"
say "stage 2: done in $((SECONDS - t)) s"

rm -f "$new"/*.log
echo "$want" >"$new/stamp"
rm -rf "$DIR"
mv "$new" "$DIR"
trap - EXIT
say "ready: $DIR/root.img ($(du -h "$DIR/root.img" | cut -f1) used) in $((SECONDS - start)) s"
