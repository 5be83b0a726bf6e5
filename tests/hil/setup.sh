#!/usr/bin/env bash
# setup.sh ARCH [CACHE]: prepares everything the HIL VM needs for ARCH (amd64 or arm64) in
# CACHE (default: $SKYLOC_HIL_CACHE, else build/hil-cache in the repository):
#
#   - host packages (QEMU, busybox, kmod, cpio, Debian's kernel headers for the current ABI);
#   - Debian's kernel image for ARCH and linux-source, fetched with `apt-get download`
#     and unpacked in the cache (nothing is installed from them);
#   - vimc, gpio-sim, gpio-mockup and irq_sim built out-of-tree (Debian's kernel has them
#     disabled), with the one patch irq_sim needs to build as a module; iio_dummy (patched
#     into a 6-axis IMU), the IIO software device/trigger framework and iio-trig-hrtimer;
#   - a bootable kernel (amd64: vmlinux extracted from the bzImage, booted through PVH);
#   - the base initramfs: static busybox and the modules with their dependencies.
#
# Every step leaves a stamp file, so a second run costs under a second. Exit status:
# 0 ready; 77 skipped (the reason is printed and kept in CACHE/ARCH/skipped, where run.sh
# finds it: no network to the Debian mirror, a package gone from the archive, not root);
# anything else is a real failure (a module that no longer builds, say).
#
# The kernel ABI (6.1.0-NN) is read from the linux-image-ARCH meta package's dependency at
# set-up time: Debian removes superseded ABIs from the archive, so it is never pinned.
set -euo pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
ARCH=${1:-}
CACHE=${2:-${SKYLOC_HIL_CACHE:-$ROOT/build/hil-cache}}
SKIP=77
JOBS=${SKYLOC_JOBS:-2}

case "$ARCH" in
  amd64) ;;
  arm64) ;;
  *)
    echo "usage: $0 amd64|arm64 [CACHE]" >&2
    exit 2
    ;;
esac

mkdir -p "$CACHE/$ARCH"
STATE="$CACHE/$ARCH"
say() { printf 'hil-setup[%s]: %s\n' "$ARCH" "$*" >&2; }
# A missing prerequisite outside our control: the tests are reported as skipped, never
# as passed, with this reason (run.sh repeats it for every test).
skip() {
  say "SKIPPED: $*"
  printf '%s\n' "$*" >"$STATE/skipped"
  rm -f "$STATE/ready.env"
  exit "$SKIP"
}
die() {
  say "FAILED: $*"
  rm -f "$STATE/ready.env" "$STATE/skipped"
  exit 1
}

# One set-up at a time per cache: the host build's and the aarch64 build's ctest runs
# may start theirs together, and both share the downloaded sources.
exec 9>"$CACHE/lock"
flock 9

start=$SECONDS
rm -f "$STATE/skipped"

# ---------------------------------------------------------------------------------------
# Host packages.
as_root() {
  if [ "$(id -u)" -eq 0 ]; then "$@"; elif command -v sudo >/dev/null && sudo -n true 2>/dev/null; then
    sudo "$@"
  else
    return 1
  fi
}
apt_updated=0
apt_update_once() {
  [ "$apt_updated" = 1 ] && return 0
  apt_updated=1
  as_root apt-get update -qq >"$CACHE/apt-update.log" 2>&1 || true
}
installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }
ensure_packages() {
  local p missing=()
  for p in "$@"; do installed "$p" || missing+=("$p"); done
  [ ${#missing[@]} -eq 0 ] && return 0
  say "installing host packages: ${missing[*]}"
  as_root true || skip "host packages missing (${missing[*]}) and not root: run ./skyloc.sh deps host"
  if ! as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
    "${missing[@]}" >"$CACHE/apt-install.log" 2>&1; then
    apt_update_once
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
      "${missing[@]}" >"$CACHE/apt-install.log" 2>&1 ||
      skip "apt-get install ${missing[*]} failed (no network to the Debian mirror? see $CACHE/apt-install.log)"
  fi
}

# apt for the guest architecture. amd64 uses the system's apt. arm64 uses a private
# configuration and state folder so /etc/apt and the host's package lists are untouched
# (no dpkg --add-architecture needed): the system's sources, the arm64 architecture only.
APT_OPTS=()
if [ "$ARCH" = arm64 ]; then
  PRIVATE_APT="$CACHE/apt-arm64"
  APT_OPTS=(-o "Dir::Etc=$PRIVATE_APT/etc" -o "Dir::State=$PRIVATE_APT/state"
    -o "Dir::Cache=$PRIVATE_APT/cache" -o "Dir::State::status=$PRIVATE_APT/status"
    -o "Dir::Etc::trusted=/etc/apt/trusted.gpg" -o "Dir::Etc::trustedparts=/etc/apt/trusted.gpg.d"
    -o APT::Architecture=arm64 -o APT::Architectures::=arm64 -o Debug::NoLocking=1)
fi
private_apt_update() {
  local d=$PRIVATE_APT
  mkdir -p "$d/etc/sources.list.d" "$d/etc/apt.conf.d" "$d/etc/preferences.d" \
    "$d/state/lists/partial" "$d/cache/archives/partial"
  : >"$d/status"
  [ -f /etc/apt/sources.list ] && cp /etc/apt/sources.list "$d/etc/"
  find /etc/apt/sources.list.d -maxdepth 1 \( -name '*.list' -o -name '*.sources' \) \
    -exec cp {} "$d/etc/sources.list.d/" \;
  if ! apt-get "${APT_OPTS[@]}" update -qq >"$d/update.log" 2>&1; then
    # Lists from an earlier update still serve a warm cache (offline runs keep working).
    [ -f "$d/updated" ] || skip "apt-get update for arm64 failed (no network to the Debian mirror? see $d/update.log)"
    say "apt-get update for arm64 failed; using the lists from $(date -r "$d/updated" +%F)"
    return 0
  fi
  touch "$d/updated"
}
guest_apt_cache() { apt-cache "${APT_OPTS[@]}" "$@"; }

# The current kernel ABI (linux-image-ARCH depends on linux-image-<ABI>-ARCH) and the
# linux-source-6.1 version, from one apt-cache call: apt-cache re-reads every package list
# on each call here (the container disables apt's binary cache), 2 s of CPU each. The
# answer only changes when the lists do, so it is kept until they are newer.
FACTS="$STATE/apt-facts.env"
apt_lists_dir() {
  if [ "$ARCH" = arm64 ]; then echo "$PRIVATE_APT/state/lists"; else apt-config dump Dir::State::lists |
    sed -n 's/^Dir::State::lists "\(.*\)";/\1/p' | sed 's|^\([^/]\)|/var/lib/apt/\1|'; fi
}
read_apt_facts() {
  ABI=
  SRC_VERSION=
  local lists
  lists=$(apt_lists_dir)
  if [ -f "$FACTS" ] && [ -d "$lists" ] && [ -z "$(find "$lists" -maxdepth 1 -newer "$FACTS" | head -1)" ]; then
    # shellcheck disable=SC1090
    . "$FACTS"
    return 0
  fi
  local info
  info=$(guest_apt_cache show --no-all-versions "linux-image-$ARCH" linux-source-6.1 2>/dev/null || true)
  ABI=$(printf '%s\n' "$info" | sed -nE "s/^Depends: linux-image-([0-9][^ ,]*)-$ARCH( .*)?\$/\1/p" | head -1)
  SRC_VERSION=$(printf '%s\n' "$info" | sed -n '/^Package: linux-source-6.1$/,/^$/s/^Version: //p' | head -1)
  if [ -n "$ABI" ] && [ -n "$SRC_VERSION" ]; then
    printf 'ABI=%s\nSRC_VERSION=%s\n' "$ABI" "$SRC_VERSION" >"$FACTS"
  fi
}

if [ "$ARCH" = arm64 ]; then
  # A day-old index is fine; a missing one is fetched.
  if [ ! -f "$PRIVATE_APT/updated" ] || [ -n "$(find "$PRIVATE_APT/updated" -mmin +1440)" ]; then
    private_apt_update
  fi
fi
read_apt_facts
if [ -z "$ABI" ] || [ -z "$SRC_VERSION" ]; then
  if [ "$ARCH" = arm64 ]; then private_apt_update; else apt_update_once; fi
  read_apt_facts
fi
[ -n "$ABI" ] || skip "apt knows no linux-image-$ARCH package (apt-get update failed or no Debian sources)"
[ -n "$SRC_VERSION" ] || skip "apt knows no linux-source-6.1 package"
KVER="$ABI-$ARCH"
HEADERS=/usr/src/linux-headers-$ABI-amd64

HOST_PKGS=(busybox-static kmod cpio bc make gcc xz-utils patch "linux-headers-$ABI-amd64")
case "$ARCH" in
  amd64)
    HOST_PKGS+=(qemu-system-x86 v4l-utils gpiod libcamera-tools libcamera-ipa dmsetup)
    ;;
  arm64)
    # The arm64 headers use the host's linux-kbuild and linux-headers-ABI-common, which
    # come with the amd64 headers package.
    HOST_PKGS+=(qemu-system-arm gcc-aarch64-linux-gnu binutils-aarch64-linux-gnu)
    ;;
esac
ensure_packages "${HOST_PKGS[@]}"

W="$STATE/$KVER"
mkdir -p "$W/stamps" "$CACHE/debs"
# A stamp holds a hash of the scripts that make its step: editing setup.sh (a module
# added, the irq_sim patch changed) or extract-vmlinux.sh redoes the build steps, not
# the downloads.
RECIPE=$(cat "$HERE/setup.sh" "$HERE/extract-vmlinux.sh" "$HERE/iio_dummy_imu.patch" | sha256sum | cut -c1-16)
stamp() { [ -f "$W/stamps/$1" ] && [ "$(cat "$W/stamps/$1")" = "$RECIPE" ]; }
done_step() { echo "$RECIPE" >"$W/stamps/$1"; }
# Unpacked downloads depend only on the package, which is in the folder's name.
fetched() { [ -f "$W/stamps/$1" ]; }
done_fetch() { touch "$W/stamps/$1"; }

# ---------------------------------------------------------------------------------------
# Downloads: apt-get download into the cache (the file name carries the version).
download() { # package[=version] -> path of the .deb (for ARCH or arch all)
  local pkg=$1 dir=$CACHE/debs name f
  name=${pkg%%=*}
  found() { find "$dir" -maxdepth 1 \( -name "${name}_*_$ARCH.deb" -o -name "${name}_*_all.deb" \) | head -1; }
  f=$(found)
  if [ -z "$f" ]; then
    say "apt-get download $pkg"
    (cd "$dir" && apt-get "${APT_OPTS[@]}" download "$pkg" >"$dir/download.log" 2>&1) ||
      skip "apt-get download $pkg failed (package gone from the archive or no network; see $dir/download.log)"
    f=$(found)
  fi
  printf '%s\n' "$f"
}

# linux-source: only the files the out-of-tree modules need are extracted (8 s of xz).
# The stamp holds the list, so a module added here re-extracts (and re-downloads) once.
SRC_PATHS=(drivers/media/test-drivers/vimc drivers/gpio/gpio-sim.c drivers/gpio/gpio-mockup.c
  drivers/gpio/gpiolib.h kernel/irq/irq_sim.c drivers/iio/dummy drivers/iio/industrialio-configfs.c
  drivers/iio/industrialio-sw-device.c drivers/iio/industrialio-sw-trigger.c
  drivers/iio/trigger/iio-trig-hrtimer.c)
SRC="$CACHE/src/linux-source-$SRC_VERSION"
if [ ! -f "$SRC/.stamp" ] || [ "$(cat "$SRC/.stamp")" != "${SRC_PATHS[*]}" ]; then
  deb=$(download "linux-source-6.1=$SRC_VERSION")
  say "extracting module sources from $(basename "$deb")"
  rm -rf "$SRC" "$SRC.tmp" && mkdir -p "$SRC.tmp"
  dpkg-deb --fsys-tarfile "$deb" | tar -x -C "$SRC.tmp" ./usr/src/linux-source-6.1.tar.xz
  tar -xJf "$SRC.tmp/usr/src/linux-source-6.1.tar.xz" -C "$SRC.tmp" --strip-components=1 \
    "${SRC_PATHS[@]/#/linux-source-6.1/}"
  rm -rf "$SRC.tmp/usr"
  mv "$SRC.tmp" "$SRC"
  printf '%s\n' "${SRC_PATHS[*]}" >"$SRC/.stamp"
  # The 139 MB source package is not needed again.
  rm -f "$deb"
fi

# The kernel image package, unpacked: the kernel and the modules we boot with.
IMG="$W/image"
if ! fetched image; then
  deb=$(download "linux-image-$KVER")
  say "unpacking $(basename "$deb")"
  rm -rf "$IMG" && mkdir -p "$IMG"
  dpkg-deb -x "$deb" "$IMG"
  rm -f "$deb"
  done_fetch image
fi
MODDIR="$IMG/lib/modules/$KVER"

# Headers. amd64: the installed package. arm64: the arm64 package unpacked in the cache;
# its Makefile includes the (architecture-independent) common headers installed on the
# host, and its scripts/tools links are pointed at the host's linux-kbuild (amd64 fixdep
# and modpost work on arm64 objects).
if [ "$ARCH" = arm64 ]; then
  HEADERS="$W/headers/usr/src/linux-headers-$KVER"
  if ! fetched headers; then
    deb=$(download "linux-headers-$KVER")
    rm -rf "$W/headers" && dpkg-deb -x "$deb" "$W/headers"
    ln -sfn /usr/lib/linux-kbuild-6.1/scripts "$HEADERS/scripts"
    ln -sfn /usr/lib/linux-kbuild-6.1/tools "$HEADERS/tools"
    rm -f "$deb"
    done_fetch headers
  fi
  MAKE_ARGS=(ARCH=arm64 CROSS_COMPILE=aarch64-linux-gnu-)
  STRIP=aarch64-linux-gnu-strip
else
  MAKE_ARGS=()
  STRIP="strip"
fi
[ -f "$HEADERS/Makefile" ] || die "kernel headers not found at $HEADERS"

# ---------------------------------------------------------------------------------------
# Out-of-tree modules. Debian builds its kernels with VIDEO_VIMC, GPIO_SIM, GPIO_MOCKUP and
# IRQ_SIM off; they build against the headers in seconds. The modules are unsigned, which
# only taints the kernel (MODULE_SIG_FORCE is off).
OOT="$W/oot"
if ! stamp oot; then
  say "building vimc, gpio-sim, gpio-mockup, irq_sim, iio_dummy, iio-trig-hrtimer out-of-tree"
  rm -rf "$OOT" && mkdir -p "$OOT/vimc" "$OOT/gpio"
  cp "$SRC"/drivers/media/test-drivers/vimc/*.[ch] "$SRC"/drivers/media/test-drivers/vimc/Makefile "$OOT/vimc/"
  cp "$SRC"/drivers/gpio/{gpio-sim.c,gpio-mockup.c,gpiolib.h} "$SRC/kernel/irq/irq_sim.c" "$OOT/gpio/"
  # irq_sim is built-in only upstream: it calls handle_simple_irq(irq_to_desc(n)), and
  # irq_to_desc is not exported to modules. generic_handle_irq(n) is the exported way to
  # run the same flow handler. A module also needs a licence line.
  grep -q 'handle_simple_irq(irq_to_desc(irqnum));' "$OOT/gpio/irq_sim.c" ||
    die "irq_sim.c in linux-source $SRC_VERSION no longer has the line the patch replaces"
  sed -i 's/handle_simple_irq(irq_to_desc(irqnum));/generic_handle_irq(irqnum);/' "$OOT/gpio/irq_sim.c"
  grep -q MODULE_LICENSE "$OOT/gpio/irq_sim.c" || echo 'MODULE_LICENSE("GPL");' >>"$OOT/gpio/irq_sim.c"
  printf 'obj-m := irq_sim.o gpio-sim.o gpio-mockup.o\n' >"$OOT/gpio/Kbuild"
  make -C "$HEADERS" M="$OOT/vimc" "${MAKE_ARGS[@]}" CONFIG_VIDEO_VIMC=m -j"$JOBS" modules \
    >"$OOT/build.log" 2>&1 || die "vimc did not build (log: $OOT/build.log)"
  make -C "$HEADERS" M="$OOT/gpio" "${MAKE_ARGS[@]}" -j"$JOBS" modules \
    >>"$OOT/build.log" 2>&1 || die "gpio-sim/irq_sim did not build (log: $OOT/build.log)"
  # IIO: Debian has the IIO core and triggered buffers but not the dummy driver, software
  # devices and triggers (configfs) or the hrtimer trigger. iio_dummy is patched into a
  # still, level 6-axis IMU (tests/hil/iio_dummy_imu.patch: accel x/y/z with a scale, +1 g
  # on z, and a 3-axis anglvel, in sysfs and in the buffer); events are left out.
  mkdir -p "$OOT/iio"
  cp "$SRC"/drivers/iio/dummy/*.[ch] "$SRC"/drivers/iio/industrialio-{configfs,sw-device,sw-trigger}.c \
    "$SRC"/drivers/iio/trigger/iio-trig-hrtimer.c "$OOT/iio/"
  patch -d "$OOT/iio" -p1 --forward --quiet <"$HERE/iio_dummy_imu.patch" >>"$OOT/build.log" 2>&1 ||
    die "tests/hil/iio_dummy_imu.patch no longer applies to linux-source $SRC_VERSION (log: $OOT/build.log)"
  cat >"$OOT/iio/Kbuild" <<'KBUILD'
obj-m := iio_dummy.o industrialio-configfs.o industrialio-sw-device.o industrialio-sw-trigger.o iio-trig-hrtimer.o
iio_dummy-y := iio_simple_dummy.o iio_simple_dummy_buffer.o
ccflags-y += -DCONFIG_IIO_SIMPLE_DUMMY_BUFFER
KBUILD
  make -C "$HEADERS" M="$OOT/iio" "${MAKE_ARGS[@]}" -j"$JOBS" modules \
    >>"$OOT/build.log" 2>&1 || die "iio_dummy/iio-trig-hrtimer did not build (log: $OOT/build.log)"
  done_step oot
fi

# ---------------------------------------------------------------------------------------
# The kernel QEMU boots. amd64: the ELF vmlinux out of the bzImage (PVH entry: no
# firmware, no decompressor). arm64: the gzip-compressed Image, which QEMU's loader
# decompresses itself.
KERNEL="$W/kernel"
if ! stamp kernel; then
  if [ "$ARCH" = amd64 ]; then
    "$HERE/extract-vmlinux.sh" "$IMG/boot/vmlinuz-$KVER" "$KERNEL" || die "could not extract vmlinux"
  else
    cp "$IMG/boot/vmlinuz-$KVER" "$KERNEL"
  fi
  done_step kernel
fi

# ---------------------------------------------------------------------------------------
# Base initramfs: static busybox and the modules with everything they depend on. The
# per-run overlay (init, test programs, their libraries) is appended by run.sh.
BASE="$W/base.cpio.gz"
# dm-flakey, loop and ext4 (which mounts ext2; it asks the crypto API for crc32c at mount
# time, so that module is named here): a route database on a block device that fails
# writes (scenario routedb_faults).
MODULES=(vivid vimc configfs irq_sim gpio-sim gpio-mockup iio_dummy iio-trig-hrtimer
  dm-flakey loop ext4 crc32c_generic)
# arm64: a virtio disk on the virt machine's virtio-mmio transport, for the Debian root
# the arm64 package test installs into (tests/package, run.sh --disk).
if [ "$ARCH" = arm64 ]; then MODULES+=(virtio_mmio virtio_blk); fi
if ! stamp base; then
  say "packing the base initramfs"
  R="$W/rootfs"
  rm -rf "$R" && mkdir -p "$R"/{bin,sbin,dev,proc,sys,run,tmp,etc,lib/modules/"$KVER"/extra}
  if [ "$ARCH" = amd64 ]; then
    cp /bin/busybox "$R/bin/busybox"
  else
    deb=$(download busybox-static)
    dpkg-deb -x "$deb" "$W/busybox"
    cp "$W/busybox/bin/busybox" "$R/bin/busybox"
  fi
  # Resolve a module name to its file: our builds first, then the image's tree.
  module_file() {
    local f
    f=$(find "$OOT" -maxdepth 2 -name "$1.ko" | head -1)
    [ -n "$f" ] || f=$(find "$MODDIR/kernel" -name "$1.ko" -o -name "$1.ko.xz" | head -1)
    [ -n "$f" ] || f=$(find "$MODDIR/kernel" -name "${1//_/-}.ko" | head -1)
    [ -n "$f" ] || f=$(find "$MODDIR/kernel" -name "${1//-/_}.ko" | head -1)
    printf '%s\n' "$f"
  }
  declare -A seen=()
  add_module() {
    local name=$1 f dep rel
    [ -n "${seen[$name]:-}" ] && return 0
    seen[$name]=1
    f=$(module_file "$name")
    if [ -z "$f" ]; then
      # Built into the kernel: nothing to copy.
      grep -qE "/${name//[-_]/[-_]}\.ko" "$MODDIR/modules.builtin" && return 0
      die "module $name not found in the image or our builds"
    fi
    case "$f" in
      "$OOT"/*) rel="extra/$(basename "$f")" ;;
      *) rel="${f#"$MODDIR"/}" ;;
    esac
    mkdir -p "$(dirname "$R/lib/modules/$KVER/$rel")"
    "$STRIP" --strip-debug -o "$R/lib/modules/$KVER/$rel" "$f"
    for dep in $(modinfo -F depends "$f" | tr ',' ' '); do add_module "$dep"; done
  }
  for m in "${MODULES[@]}"; do add_module "$m"; done
  cp "$MODDIR"/modules.builtin "$MODDIR"/modules.builtin.modinfo "$MODDIR"/modules.order \
    "$R/lib/modules/$KVER/" 2>/dev/null || true
  depmod -b "$R" "$KVER" || die "depmod failed on the initramfs tree"
  printf '%s\n' "${!seen[@]}" | sort >"$W/modules.list"
  (cd "$R" && find . | LC_ALL=C sort | cpio -o -H newc --quiet -R 0:0) | gzip -1 >"$BASE.tmp"
  mv "$BASE.tmp" "$BASE"
  rm -rf "$R"
  done_step base
fi

# ---------------------------------------------------------------------------------------
# arm64 guest tools: the host's v4l-utils and libgpiod tools are amd64 programs, so the
# arm64 image gets Debian's arm64 builds, with their whole dependency closure, downloaded
# through the private apt (empty dpkg status: every dependency is fetched) and unpacked
# into a sysroot that run.sh takes programs and libraries from.
SYSROOT=
if [ "$ARCH" = arm64 ]; then
  SYSROOT="$W/sysroot"
  GUEST_TOOLS=(v4l-utils gpiod dmsetup)
  # The stamp names the packages: adding one fetches the sysroot again.
  tools_stamp="sysroot-$(printf '%s-' "${GUEST_TOOLS[@]}")"
  if ! fetched "$tools_stamp"; then
    say "downloading arm64 ${GUEST_TOOLS[*]} with their dependencies"
    archives="$CACHE/debs/arm64-tools"
    rm -rf "$archives" "$SYSROOT" && mkdir -p "$archives/partial" "$SYSROOT"
    apt-get "${APT_OPTS[@]}" -o "Dir::Cache::archives=$archives" --no-install-recommends -y -qq \
      install --download-only "${GUEST_TOOLS[@]}" >"$archives/download.log" 2>&1 ||
      skip "apt-get could not download arm64 ${GUEST_TOOLS[*]} (see $archives/download.log)"
    for deb in "$archives"/*.deb; do dpkg-deb -x "$deb" "$SYSROOT"; done
    rm -rf "$archives"
    done_fetch "$tools_stamp"
  fi
fi

# Superseded kernel ABIs and source versions (Debian moved on): their folders go.
find "$STATE" -mindepth 1 -maxdepth 1 -type d ! -name "$KVER" -exec rm -rf {} +
find "$CACHE/src" -mindepth 1 -maxdepth 1 -type d ! -name "linux-source-$SRC_VERSION" -exec rm -rf {} +

cat >"$STATE/ready.env" <<EOF
HIL_ARCH=$ARCH
HIL_KVER=$KVER
HIL_KERNEL=$KERNEL
HIL_BASE_INITRD=$BASE
HIL_GUEST_SYSROOT=$SYSROOT
EOF
say "ready: kernel $KVER, $(wc -l <"$W/modules.list") modules ($((SECONDS - start)) s)"
