#!/usr/bin/env bash
# run.sh: boots the HIL VM (QEMU, TCG) with real kernel test drivers and runs scenarios.
#
#   run.sh --arch amd64|arm64 --tests a,b [--bin FILE]... [--name NAME] [--log FILE]
#          [--timeout SECONDS] [--cache DIR] [--lib-sysroot DIR] [--file FILE]...
#          [--disk IMAGE | --snapshot-disk IMAGE] [--scenario-timeout SECONDS]
#
# --tests   scenarios from tests/hil/guest/<name>.sh, run in order inside the VM
# --bin     a program copied to /hil/bin in the guest, with the shared libraries it needs
#           (resolved from its ELF NEEDED entries; arm64 ones from the cross sysroot)
# --lib-sysroot  the cross build's target sysroot (build/sysroot-arm64): the libraries
#           (and the loader) the --bin programs were linked against, searched first
# --log     where the guest console goes (default build/hil-logs/NAME.log)
# --file    a data file copied to /hil/files in the guest (a .deb, a script)
# --disk    (arm64) a raw disk image the guest sees as /dev/vda; its writes are kept
# --snapshot-disk  the same, but the guest's writes go to a temporary overlay QEMU
#           discards, so IMAGE stays as it was (a cached image shared by test runs)
# --scenario-timeout  the guest's limit for each scenario (default 240 s, inside --timeout)
#
# Needs tests/hil/setup.sh ARCH to have run (CTest: the hil.setup fixture). Exit status:
# the guest's HIL-RESULT rc (0 passed, 77 skipped); 77 with the reason when the set-up
# was skipped; 2 when the guest printed no result (panic, hang, timeout), with the last
# console lines shown.
set -euo pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
SKIP=77
ARCH=
TESTS=
NAME=
LOG=
TIMEOUT=300
CACHE=${SKYLOC_HIL_CACHE:-$ROOT/build/hil-cache}
BINS=()
FILES=()
LIB_SYSROOT=
DISK=
DISK_SNAPSHOT=off
SCENARIO_TIMEOUT=240
while [ $# -gt 0 ]; do
  case "$1" in
    --arch) ARCH=$2 ;;
    --tests) TESTS=$2 ;;
    --bin) BINS+=("$2") ;;
    --name) NAME=$2 ;;
    --log) LOG=$2 ;;
    --timeout) TIMEOUT=$2 ;;
    --cache) CACHE=$2 ;;
    --lib-sysroot) LIB_SYSROOT=$2 ;;
    --file) FILES+=("$2") ;;
    --disk) DISK=$2 DISK_SNAPSHOT=off ;;
    --snapshot-disk) DISK=$2 DISK_SNAPSHOT=on ;;
    --scenario-timeout) SCENARIO_TIMEOUT=$2 ;;
    *)
      sed -n '2,23p' "$0" >&2
      exit 2
      ;;
  esac
  shift 2
done
if [ -z "$ARCH" ] || [ -z "$TESTS" ]; then
  sed -n '2,23p' "$0" >&2
  exit 2
fi
NAME=${NAME:-hil.$ARCH.${TESTS//,/+}}
LOG=${LOG:-$ROOT/build/hil-logs/$NAME.log}
STATE="$CACHE/$ARCH"

if [ -f "$STATE/skipped" ]; then
  echo "HIL SKIPPED: set-up for $ARCH did not run: $(cat "$STATE/skipped")"
  exit $SKIP
fi
if [ ! -f "$STATE/ready.env" ]; then
  echo "HIL SKIPPED: no VM image for $ARCH in $CACHE: run tests/hil/setup.sh $ARCH (ctest runs it as hil.setup.$ARCH)"
  exit $SKIP
fi
# shellcheck disable=SC1091
. "$STATE/ready.env"

case "$ARCH" in
  amd64)
    QEMU=qemu-system-x86_64
    # -M pc with the ELF vmlinux: QEMU enters it through the PVH note (no firmware, no
    # decompressor). TCG: this machine has no usable hardware virtualisation.
    MACHINE=(-M pc -cpu max)
    CONSOLE=ttyS0
    LIBDIRS=(/lib/x86_64-linux-gnu /usr/lib/x86_64-linux-gnu /lib64 /usr/lib /lib)
    READELF=readelf
    ;;
  arm64)
    QEMU=qemu-system-aarch64
    # cortex-a53: -cpu max emulates pointer authentication, which makes TCG 4x slower.
    MACHINE=(-M virt -cpu cortex-a53)
    CONSOLE=ttyAMA0
    # Debian's arm64 libraries: first the cross build's sysroot (what the programs were
    # linked against: libcamera, libgpiod, libc), then the set-up's sysroot (the guest
    # tools' libraries), then the cross toolchain's for what both lack. The loader comes
    # from the first of the two sysroots, so that it matches that libc.
    LIBDIRS=()
    for r in $LIB_SYSROOT $HIL_GUEST_SYSROOT; do
      LIBDIRS+=("$r/lib/aarch64-linux-gnu" "$r/usr/lib/aarch64-linux-gnu")
    done
    LIBDIRS+=(/usr/aarch64-linux-gnu/lib)
    LOADER_ROOT=${LIB_SYSROOT:-$HIL_GUEST_SYSROOT}
    READELF=aarch64-linux-gnu-readelf
    command -v "$READELF" >/dev/null || READELF=readelf
    ;;
  *)
    echo "run.sh: unknown --arch $ARCH" >&2
    exit 2
    ;;
esac
command -v "$QEMU" >/dev/null || {
  echo "HIL SKIPPED: $QEMU is not installed (./skyloc.sh deps host)"
  exit $SKIP
}

# ---------------------------------------------------------------------------------------
# The per-run overlay: /init, the scenarios, the programs and their libraries. The kernel
# unpacks every cpio archive in the initrd in turn, so it is simply appended to the base.
WORK=$(mktemp -d "${TMPDIR:-/tmp}/skyloc-hil.XXXXXX")
trap 'rm -rf "$WORK"' EXIT
OV="$WORK/overlay"
mkdir -p "$OV/hil/bin" "$OV/hil/lib" "$OV/hil/tests"
cp "$HERE/init" "$OV/init"
chmod 755 "$OV/init"
cp "$HERE"/guest/*.sh "$OV/hil/tests/"

declare -A copied=()
# Sets lib to the first DIR/$soname of the run path given and LIBDIRS.
find_lib() {
  local d
  for d in "$@" "${LIBDIRS[@]}"; do
    [ -e "$d/$soname" ] && lib=$d/$soname && return 0
  done
  return 1
}
# Copies FILE's shared libraries (transitively) to /hil/lib and its loader to the path
# its PT_INTERP names. readelf rather than ldd, so that cross-built programs resolve too.
# One readelf a file, read by bash's own matching: a VM test copies a hundred or more
# libraries, and a pipeline of readelf, sed and tr for each of interpreter, run path and
# needed names (about nine processes a library) made this the longest part of a run
# before QEMU started (24 s of a 44 s test on a loaded machine).
add_libs() {
  local file=$1 line interp='' soname lib d
  local runpath=() needed=() parts=()
  local re_interp='Requesting program interpreter: (.*)]'
  local re_needed='[(]NEEDED[)].*[[](.*)[]]'
  local re_runpath='[(]R(UN)?PATH[)].*[[](.*)[]]'
  while IFS= read -r line; do
    if [[ $line =~ $re_interp ]]; then
      interp=${BASH_REMATCH[1]}
    elif [[ $line =~ $re_needed ]]; then
      needed+=("${BASH_REMATCH[1]}")
    elif [[ $line =~ $re_runpath ]]; then
      IFS=: read -ra parts <<<"${BASH_REMATCH[2]}"
      for d in "${parts[@]}"; do runpath+=("${d//\$ORIGIN/${file%/*}}"); done
    fi
  done < <("$READELF" -W -l -d "$file" 2>/dev/null)
  if [ -n "$interp" ] && [ -z "${copied[$interp]:-}" ]; then
    copied[$interp]=1
    local real=$interp
    [ "$ARCH" = arm64 ] && real=$LOADER_ROOT$interp
    mkdir -p "$OV${interp%/*}"
    cp -L "$real" "$OV$interp"
  fi
  for soname in "${needed[@]}"; do
    [ -n "${copied[$soname]:-}" ] && continue
    copied[$soname]=1
    find_lib "${runpath[@]}" || {
      echo "run.sh: $soname (needed by $file) not found in ${LIBDIRS[*]}" >&2
      exit 1
    }
    cp -L "$lib" "$OV/hil/lib/$soname"
    add_libs "$lib"
  done
}
add_program() { # host path [guest dir]
  local dest=${2:-/hil/bin}
  mkdir -p "$OV$dest"
  cp -L "$1" "$OV$dest/"
  add_libs "$1"
}

for b in "${BINS[@]}"; do
  [ -f "$b" ] || {
    echo "run.sh: --bin $b does not exist (build it first)" >&2
    exit 1
  }
  add_program "$b"
done
if [ ${#FILES[@]} -gt 0 ]; then
  mkdir -p "$OV/hil/files"
  for f in "${FILES[@]}"; do
    [ -f "$f" ] || {
      echo "run.sh: --file $f does not exist" >&2
      exit 1
    }
    cp -L "$f" "$OV/hil/files/"
  done
fi
# Debian's own tools for the baseline checks and for setting up vimc's media graph:
# v4l-utils and libgpiod's tools (for arm64 from the set-up's arm64 sysroot), and on
# amd64 libcamera's cam.
# dmsetup for the route database on a failing block device (routedb_faults).
TOOLS=(v4l2-ctl media-ctl gpiodetect gpioinfo gpioget gpioset dmsetup)
if [ "$ARCH" = arm64 ]; then
  for p in "${TOOLS[@]}"; do
    for d in usr/bin usr/sbin sbin bin; do
      if [ -f "$HIL_GUEST_SYSROOT/$d/$p" ]; then
        add_program "$HIL_GUEST_SYSROOT/$d/$p"
        break
      fi
    done
  done
  # A cross build with libcamera: vimc's IPA module and its data from the build's sysroot
  # (libcamera loads them from fixed paths).
  LCDIR=/usr/lib/aarch64-linux-gnu/libcamera
  if [ -n "$LIB_SYSROOT" ] && [ -f "$LIB_SYSROOT$LCDIR/ipa_vimc.so" ]; then
    for f in ipa_vimc.so vimc_ipa_proxy; do add_program "$LIB_SYSROOT$LCDIR/$f" "$LCDIR"; done
    cp "$LIB_SYSROOT$LCDIR/ipa_vimc.so.sign" "$OV$LCDIR/"
    mkdir -p "$OV/usr/share/libcamera/ipa"
    cp -r "$LIB_SYSROOT/usr/share/libcamera/ipa/vimc" "$OV/usr/share/libcamera/ipa/"
  fi
else
  for p in "${TOOLS[@]}" cam; do add_program "$(PATH=$PATH:/usr/sbin:/sbin command -v "$p")"; done
  # libcamera loads its IPA modules and their data from fixed paths.
  LCDIR=/usr/lib/x86_64-linux-gnu/libcamera
  for f in "$LCDIR"/ipa_vimc.so "$LCDIR"/vimc_ipa_proxy; do add_program "$f" "$LCDIR"; done
  cp "$LCDIR/ipa_vimc.so.sign" "$OV$LCDIR/"
  mkdir -p "$OV/usr/share/libcamera/ipa"
  cp -r /usr/share/libcamera/ipa/vimc "$OV/usr/share/libcamera/ipa/"
fi

(cd "$OV" && find . | LC_ALL=C sort | cpio -o -H newc --quiet -R 0:0) >"$WORK/overlay.cpio"
# An uncompressed archive after a compressed one must start on a 4-byte boundary; the
# kernel skips the zero padding.
base_size=$(stat -c %s "$HIL_BASE_INITRD")
{
  cat "$HIL_BASE_INITRD"
  head -c $(((4 - base_size % 4) % 4)) /dev/zero
  cat "$WORK/overlay.cpio"
} >"$WORK/initrd"

# ---------------------------------------------------------------------------------------
mkdir -p "$(dirname "$LOG")"
APPEND="console=$CONSOLE quiet loglevel=4 panic=-1 rdinit=/init hil.tests=$TESTS hil.timeout=$SCENARIO_TIMEOUT"
# shellcheck disable=SC2054 # the commas are QEMU's option syntax
CMD=("$QEMU" -accel tcg,thread=multi "${MACHINE[@]}" -m 1024 -smp 1 -nodefaults -no-user-config
  -display none -serial stdio -monitor none -no-reboot
  -kernel "$HIL_KERNEL" -initrd "$WORK/initrd" -append "$APPEND")
if [ -n "$DISK" ]; then
  [ -f "$DISK" ] || {
    echo "run.sh: disk image $DISK does not exist" >&2
    exit 1
  }
  # virtio-mmio: the virt machine's own transport (virtio_mmio and virtio_blk are in the
  # arm64 initramfs); the pc machine would need virtio-pci, which the amd64 one lacks.
  [ "$ARCH" = arm64 ] || {
    echo "run.sh: --disk is for --arch arm64 only (the amd64 initramfs has no virtio_pci)" >&2
    exit 2
  }
  # shellcheck disable=SC2054 # the commas are QEMU's option syntax
  CMD+=(-drive "file=$DISK,format=raw,if=none,id=disk0,snapshot=$DISK_SNAPSHOT"
    -device virtio-blk-device,drive=disk0)
fi
echo "run.sh: ${CMD[*]}" >"$LOG"
echo "run.sh: console log: $LOG"
start=$(date +%s.%N)
rc=0
# panic=-1 with -no-reboot makes QEMU exit on a kernel panic; timeout catches a hang.
# TMPDIR: QEMU's overlay for --snapshot-disk goes in the work folder, which is removed.
TMPDIR=$WORK timeout --foreground -k 5 "$TIMEOUT" "${CMD[@]}" </dev/null 2>&1 | tr -d '\r' | tee -a "$LOG" || rc=$?
elapsed=$(echo "$(date +%s.%N) - $start" | bc)
printf 'run.sh: %s: guest ran %.1f s\n' "$NAME" "$elapsed" | tee -a "$LOG"

result=$(sed -n 's/^HIL-RESULT: rc=\([0-9]*\).*/\1/p' "$LOG" | tail -1)
if [ -z "$result" ]; then
  echo "run.sh: the guest printed no HIL-RESULT (kernel panic, hang or timeout after ${TIMEOUT} s; qemu status $rc). Last console lines:"
  tail -n 40 "$LOG" | sed 's/^/  | /'
  exit 2
fi
if [ "$result" = "$SKIP" ]; then
  echo "HIL SKIPPED: a scenario in the guest skipped (PENDING lines say why; see $LOG)"
fi
exit "$result"
