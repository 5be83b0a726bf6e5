#!/usr/bin/env bash
# extract-vmlinux.sh BZIMAGE OUT: writes the uncompressed ELF kernel held in a bzImage.
#
# QEMU boots an ELF vmlinux through its PVH note, which skips the firmware and the
# in-guest decompressor (about 3 s under TCG). A bzImage is a real-mode stub plus a
# compressed payload; we look for each compressor's magic bytes, decompress from there and
# keep the first result that starts with the ELF magic (the approach of the kernel tree's
# scripts/extract-vmlinux; written here for the project).
set -euo pipefail

[ $# -eq 2 ] || {
  echo "usage: $0 BZIMAGE OUT" >&2
  exit 2
}
image=$1
out=$2
tmp="$out.part"
trap 'rm -f "$tmp"' EXIT

# magic (grep -P escape) | decompressor reading stdin. xz --single-stream and the others
# stop at the end of the stream and ignore the bytes that follow it in the image.
decoders=(
  '\xfd\x37\x7a\x58\x5a\x00|xz -dc --single-stream'
  '\x1f\x8b\x08|gzip -dc'
  '\x28\xb5\x2f\xfd|zstd -dcq'
  '\x5d\x00\x00\x00|xz -dc --format=lzma'
  '\x02\x21\x4c\x18|lz4 -dc'
)

for entry in "${decoders[@]}"; do
  magic=${entry%%|*}
  decoder=${entry#*|}
  command -v "${decoder%% *}" >/dev/null || continue
  while read -r offset; do
    # A decoder complains about the trailing bytes after the stream; what counts is the
    # output, so its exit status and messages are ignored.
    tail -c "+$((offset + 1))" "$image" | $decoder >"$tmp" 2>/dev/null || true
    if [ "$(head -c 4 "$tmp" | od -An -tx1 | tr -d ' \n')" = "7f454c46" ]; then
      mv "$tmp" "$out"
      exit 0
    fi
  done < <(LC_ALL=C grep -obUaP "$magic" "$image" | cut -d: -f1)
done
echo "extract-vmlinux: no compressed ELF kernel found in $image" >&2
exit 1
