#!/bin/sh
# The checks of an installed skyloc .deb, shared by both package tests: $1 is a Debian root
# in which apt has just installed skyloc_*.deb. package.deb_host (deb_test.sh) runs it as
# mmdebstrap's customize hook on the build machine; package.deb_arm64 in the arm64 HIL VM
# (tests/hil/guest/deb_install.sh), under busybox sh, on the arm64 root on its disk.
# Prints "in-root: ..." lines; exits non-zero on the first thing that is wrong.
set -eu
root=$1
fail() {
  echo "in-root: FAILED: $*" >&2
  exit 1
}
# The root's programs through its own env, by absolute path, in a plain environment: the
# VM's busybox chroot would otherwise run its own applets (dpkg, id, stat) for names
# without a path, and the VM's LD_LIBRARY_PATH is for its initramfs.
in_root() { chroot "$root" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin HOME=/root LC_ALL=C "$@"; }

version=$(in_root /usr/bin/skyloc --version) || fail "/usr/bin/skyloc --version does not run"
echo "in-root: /usr/bin/skyloc --version: $version"
in_root /usr/bin/skyloc demo --quick >"$root/demo.log" 2>&1 || fail "skyloc demo --quick: $(tail -5 "$root/demo.log")"
echo "in-root: skyloc demo --quick: $(tail -1 "$root/demo.log")"
rm -f "$root/demo.log"

groups=$(in_root id -nG skyloc) || fail "no user skyloc"
for g in video gpio; do
  case " $groups " in *" $g "*) ;; *) fail "user skyloc is not in group $g (groups: $groups)" ;; esac
done
echo "in-root: user skyloc, groups: $groups"
owner=$(in_root stat -c %U:%G /var/lib/skyloc) || fail "/var/lib/skyloc missing"
[ "$owner" = skyloc:skyloc ] || fail "/var/lib/skyloc belongs to $owner, not skyloc:skyloc"
[ -f "$root/etc/skyloc/skyloc.toml" ] || fail "/etc/skyloc/skyloc.toml missing"
# shellcheck disable=SC2016 # dpkg-query's format
in_root dpkg-query -W -f='${Conffiles}\n' skyloc | grep -q "/etc/skyloc/skyloc.toml" ||
  fail "/etc/skyloc/skyloc.toml is not a conffile"
[ -f "$root/lib/systemd/system/skyloc.service" ] || fail "the systemd unit is missing"

# A taught route is data: remove keeps it (and the configuration), purge keeps the route
# and removes the configuration.
echo route >"$root/var/lib/skyloc/route.db"
in_root dpkg --remove skyloc >/dev/null || fail "dpkg --remove skyloc"
[ ! -e "$root/usr/bin/skyloc" ] || fail "remove left /usr/bin/skyloc"
[ -f "$root/var/lib/skyloc/route.db" ] || fail "remove deleted /var/lib/skyloc/route.db"
[ -f "$root/etc/skyloc/skyloc.toml" ] || fail "remove deleted the configuration (only purge may)"
echo "in-root: remove: binary gone, /var/lib/skyloc/route.db and /etc/skyloc/skyloc.toml kept"
in_root dpkg --purge skyloc >/dev/null || fail "dpkg --purge skyloc"
[ ! -e "$root/etc/skyloc" ] || fail "purge left /etc/skyloc"
[ -f "$root/var/lib/skyloc/route.db" ] || fail "purge deleted /var/lib/skyloc/route.db"
echo "in-root: purge: /etc/skyloc gone, /var/lib/skyloc/route.db kept"
