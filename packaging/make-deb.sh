#!/usr/bin/env bash
# Builds the Debian package skyloc_<version>_<arch>.deb from a built skyloc binary with
# dpkg-deb (docs/PACKAGING.md). ./skyloc.sh package calls it with a Release build; the
# CTest test package.deb_host calls it with the test build's binary.
#
#   packaging/make-deb.sh BINARY DEB_ARCH OUT_DIR [SYSROOT]
#
# DEB_ARCH is Debian's name (amd64, arm64, armhf). For a cross-built binary, SYSROOT is
# the target sysroot (build/sysroot-<arch>): dpkg-shlibdeps finds the libraries there and
# takes their dependency information from the shlibs files ./skyloc.sh kept from its
# packages. Prints the path of the .deb.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
die() {
  printf 'make-deb: error: %s\n' "$*" >&2
  exit 1
}
if [ $# -lt 3 ] || [ $# -gt 4 ]; then die "usage: packaging/make-deb.sh BINARY DEB_ARCH OUT_DIR [SYSROOT]"; fi
binary=$(realpath -m "$1") arch=$2 out=$(realpath -m "$3") sysroot=${4:+$(realpath -m "$4")}
[ -x "$binary" ] || die "no skyloc binary at $binary: build it first (./skyloc.sh build)"
for tool in dpkg-deb dpkg-shlibdeps dpkg-parsechangelog; do
  command -v "$tool" >/dev/null || die "$tool is missing: apt-get install dpkg-dev"
done

version=$(sed -nE 's/^project\(skyloc VERSION ([0-9.]+).*/\1/p' "$ROOT/CMakeLists.txt")
[ -n "$version" ] || die "cannot read the version from project(skyloc VERSION ...) in CMakeLists.txt"
changelog_version=$(dpkg-parsechangelog -l "$ROOT/packaging/changelog" -S Version)
[ "$changelog_version" = "$version" ] ||
  die "packaging/changelog's newest entry is $changelog_version but CMakeLists.txt says $version: add a changelog entry (dch -v $version -c packaging/changelog)"

host_arch=$(dpkg --print-architecture)
gnu_type=$(dpkg-architecture -a"$arch" -qDEB_HOST_GNU_TYPE 2>/dev/null) || die "unknown Debian architecture '$arch'"
multiarch=$(dpkg-architecture -a"$arch" -qDEB_HOST_MULTIARCH 2>/dev/null)
strip="strip"
if [ "$arch" != "$host_arch" ]; then
  if [ -z "$sysroot" ] || [ ! -f "$sysroot/skyloc-sysroot/shlibs" ]; then
    die "packaging for $arch needs the $arch sysroot (./skyloc.sh deps makes build/sysroot-$arch) as the 4th argument"
  fi
  strip=$gnu_type-strip
fi
command -v "$strip" >/dev/null || die "$strip is missing (binutils for $arch: apt-get install binutils-$gnu_type)"

# Everything happens in a scratch folder beside the output, removed on exit.
mkdir -p "$out"
work=$(mktemp -d "$out/.make-deb.XXXXXX")
trap 'rm -rf "$work"' EXIT
pkg=$work/skyloc
install -d "$pkg/DEBIAN" "$pkg/usr/bin" "$pkg/etc/skyloc" "$pkg/lib/systemd/system" \
  "$pkg/usr/lib/sysusers.d" "$pkg/usr/share/doc/skyloc" "$pkg/usr/share/lintian/overrides"
install -m 0755 "$binary" "$pkg/usr/bin/skyloc"
"$strip" --strip-unneeded --remove-section=.comment --remove-section=.note "$pkg/usr/bin/skyloc"
install -m 0644 "$ROOT/config/skyloc.toml" "$pkg/etc/skyloc/skyloc.toml"
install -m 0644 "$ROOT/config/skyloc.service" "$pkg/lib/systemd/system/skyloc.service"
install -m 0644 "$ROOT/packaging/sysusers.conf" "$pkg/usr/lib/sysusers.d/skyloc.conf"
install -m 0644 "$ROOT/packaging/copyright" "$pkg/usr/share/doc/skyloc/copyright"
install -m 0644 "$ROOT/README.md" "$pkg/usr/share/doc/skyloc/README.md"
gzip -9n <"$ROOT/packaging/changelog" >"$pkg/usr/share/doc/skyloc/changelog.gz"
chmod 0644 "$pkg/usr/share/doc/skyloc/changelog.gz"
install -m 0644 "$ROOT/packaging/lintian-overrides" "$pkg/usr/share/lintian/overrides/skyloc"
# The ROS 2 message package of the DDS output, for the user to build in a ROS 2 workspace
# (docs/OUTPUTS.md).
install -d "$pkg/usr/share/skyloc/skyloc_msgs/msg"
install -m 0644 "$ROOT/skyloc_msgs/package.xml" "$ROOT/skyloc_msgs/CMakeLists.txt" "$pkg/usr/share/skyloc/skyloc_msgs/"
install -m 0644 "$ROOT/skyloc_msgs/msg/Localisation.msg" "$pkg/usr/share/skyloc/skyloc_msgs/msg/"
install -m 0755 "$ROOT/packaging/postinst" "$ROOT/packaging/prerm" "$ROOT/packaging/postrm" "$pkg/DEBIAN/"
echo /etc/skyloc/skyloc.toml >"$pkg/DEBIAN/conffiles"

# Depends: the shared libraries the binary links (dpkg-shlibdeps), plus what postinst runs.
mkdir -p "$work/debian"
printf 'Source: skyloc\n\nPackage: skyloc\nArchitecture: any\n' >"$work/debian/control"
shlibdeps_args=(-O "-e$pkg/usr/bin/skyloc")
if [ "$arch" != "$host_arch" ]; then
  shlibdeps_args+=("-L$sysroot/skyloc-sysroot/shlibs" "-l$sysroot/lib/$multiarch" "-l$sysroot/usr/lib/$multiarch")
fi
shlibs=$(cd "$work" && DEB_HOST_ARCH=$arch dpkg-shlibdeps "${shlibdeps_args[@]}" 2>"$work/shlibdeps.log") || {
  cat "$work/shlibdeps.log" >&2
  die "dpkg-shlibdeps failed for $binary ($arch)"
}
[ ! -s "$work/shlibdeps.log" ] || cat "$work/shlibdeps.log" >&2
depends=${shlibs#shlibs:Depends=}
if [ -z "$depends" ] || [ "$depends" = "$shlibs" ]; then die "dpkg-shlibdeps printed no Depends for $binary: $shlibs"; fi
depends="$depends, systemd | systemd-standalone-sysusers | systemd-sysusers"

installed_size=$(du -sk --exclude=DEBIAN "$pkg" | cut -f1)
cat >"$pkg/DEBIAN/control" <<CONTROL
Package: skyloc
Version: $version
Architecture: $arch
Maintainer: $(dpkg-parsechangelog -l "$ROOT/packaging/changelog" -S Maintainer)
Installed-Size: $installed_size
Depends: $depends
Section: misc
Priority: optional
Description: sky-shape place recognition for small robots
 skyloc localises a robot along a taught route from the shape of the sky
 seen by an upward camera: teach records a route, repeat localises against
 it and drives status lines (GPIO), replay runs a recording through the
 same pipeline.
 .
 The package installs the skyloc.service unit (not enabled: teach a route
 first), the skyloc system user in the video and gpio groups, and
 /etc/skyloc/skyloc.toml. Taught routes live in /var/lib/skyloc, which
 removing or purging the package keeps.
CONTROL

deb="$out/skyloc_${version}_${arch}.deb"
# Files owned by root whatever user builds; reproducible: the mtimes of the changelog date.
SOURCE_DATE_EPOCH=$(dpkg-parsechangelog -l "$ROOT/packaging/changelog" -S Timestamp)
export SOURCE_DATE_EPOCH
find "$pkg" -exec touch --no-dereference --date="@$SOURCE_DATE_EPOCH" {} +
dpkg-deb --root-owner-group -Zxz --build "$pkg" "$deb" >/dev/null
echo "$deb"
