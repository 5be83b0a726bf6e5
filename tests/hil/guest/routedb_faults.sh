# The route database on storage that really fails, made by the kernel:
#   1. a block device that starts failing every write mid-teach: a device-mapper table
#      switched from `linear` to `flakey ... error_writes` over a loop device holding an
#      ext2 file system. skyloc teach must report the failure and exit 1, keep every
#      flushed frame on the disk, and `skyloc route recover` must make the file load
#      again (checked after a remount, so the page cache cannot hide what the disk holds);
#   2. a file system that fills up (tmpfs of 48 KiB): teach reports what it kept, commits
#      the frames that fit, and the route loads strictly.
# The camera is the simulated one (this is about the disk, not the camera).
# shellcheck source=tests/hil/guest/lib.sh
. /hil/tests/lib.sh

SKYLOC=/hil/bin/skyloc
[ -x "$SKYLOC" ] || pending "skyloc is not in this image"
have dmsetup || pending "dmsetup is not in this image"
for m in loop dm-flakey crc32c_generic ext4; do
  modprobe "$m" || {
    bad "modprobe $m failed"
    finish_scenario
  }
done
# No udevd here: libdevmapper makes /dev/mapper nodes itself.
export DM_DISABLE_UDEV=1

CONFIG=/tmp/skyloc_faults.toml
cat >"$CONFIG" <<EOF
[camera]
kind = "sim"
sim_world = "street"
width = 96
height = 96
fps = 200.0

[descriptor]
bands = 24

[capacities]
route_frames = 100000

[route_db]
flush_every = 10
EOF

size_of() { # FILE -> its size in bytes, 0 when it does not exist
  if [ -f "$1" ]; then file_size "$1"; else echo 0; fi
}
frames_in() { # route info output -> its frame count
  sed -n 's/.*: \([0-9][0-9]*\) frames in .*/\1/p' "$1" | head -n 1
}

echo "1. writes fail mid-teach: dm-flakey with error_writes under ext2"
truncate -s 32M /tmp/disk.img
LOOP=$(losetup -f)
losetup "$LOOP" /tmp/disk.img || {
  bad "losetup $LOOP failed"
  finish_scenario
}
SECTORS=$((32 * 1024 * 1024 / 512))
dmsetup create skylocdb --table "0 $SECTORS linear $LOOP 0" || {
  bad "dmsetup create failed"
  finish_scenario
}
mke2fs -q /dev/mapper/skylocdb >/dev/null 2>&1 || bad "mke2fs failed"
mkdir -p /mnt/db
mount -t ext2 /dev/mapper/skylocdb /mnt/db || {
  bad "mount of the dm device failed"
  finish_scenario
}
ROUTE=/mnt/db/route.db
"$SKYLOC" teach --route "$ROUTE" --config "$CONFIG" >/dev/null 2>/tmp/faults-teach.err &
skyloc=$!
# Let it write a few hundred frames (a record is 464 bytes here; each chunk of 10 is
# fdatasync'ed).
i=0
while [ "$(size_of "$ROUTE")" -lt 200000 ] && kill -0 "$skyloc" 2>/dev/null && [ "$i" -lt 300 ]; do
  sleep 0.1
  i=$((i + 1))
done
echo "  the route holds $(size_of "$ROUTE") bytes; every write fails from now on"
switch_table() { # TABLE: swap the device's table, as a fault would (suspend, load, resume)
  # --nolockfs --noflush: freezing the file system would write, and writes may be failing.
  if ! { dmsetup suspend --nolockfs --noflush skylocdb && dmsetup load skylocdb --table "$1" &&
    dmsetup resume skylocdb; }; then
    bad "could not switch the table to: $1"
  fi
}
switch_table "0 $SECTORS flakey $LOOP 0 0 1 1 error_writes"
if ! wait_gone "$skyloc" 30; then
  bad "teach still running 30 s after its writes started failing"
  kill -9 "$skyloc"
fi
wait "$skyloc"
rc=$?
expect_eq "teach exit status on failing writes" "$rc" 1
kept=$(sed -n 's/.*: \([0-9][0-9]*\) frames kept on the disk but NOT committed.*/\1/p' /tmp/faults-teach.err | head -n 1)
# The file to recover, as teach names it.
ROUTE=$(sed -n "s/.*run 'skyloc route recover \([^']*\)'.*/\1/p" /tmp/faults-teach.err | head -n 1)
if [ -n "$kept" ] && [ -n "$ROUTE" ]; then
  ok "teach said what it kept and how to recover: $kept frames, route recover $ROUTE"
  # An I/O error is not a full disk: the hint must not say to free space.
  grep -q "check the storage" /tmp/faults-teach.err || bad "the hint for an I/O error does not point at the storage"
else
  bad "teach did not say what it kept and to run route recover"
fi
grep -v '^ *[a-z]* *[0-9]' /tmp/faults-teach.err | sed 's/^/       | /' | tail -n 4
# The disk works again; drop the page cache's view by remounting.
switch_table "0 $SECTORS linear $LOOP 0"
umount /mnt/db 2>/dev/null || umount -l /mnt/db
mount -t ext2 /dev/mapper/skylocdb /mnt/db || bad "remount failed"
"$SKYLOC" route info "$ROUTE" >/tmp/faults-info.out 2>&1
if grep -q "NOT committed" /tmp/faults-info.out; then
  ok "on the disk after the remount: $(head -n 1 /tmp/faults-info.out | cut -c1-100)"
else
  bad "route info after the fault: $(cat /tmp/faults-info.out)"
fi
if "$SKYLOC" route recover "$ROUTE" >/tmp/faults-recover.out 2>&1; then
  ok "route recover: $(head -n 1 /tmp/faults-recover.out | cut -c1-140)"
else
  bad "route recover failed: $(cat /tmp/faults-recover.out)"
fi
if "$SKYLOC" route info "$ROUTE" >/tmp/faults-info.out 2>&1 && grep -q ", committed" /tmp/faults-info.out; then
  got=$(frames_in /tmp/faults-info.out)
  if [ -n "$kept" ] && [ "${got:-0}" -ge "$kept" ]; then
    ok "recovered route loads: $got frames (teach said $kept were on the disk)"
  else
    bad "recovered route has ${got:-?} frames, teach said ${kept:-?} were on the disk"
  fi
else
  bad "recovered route does not load: $(cat /tmp/faults-info.out)"
fi

umount /mnt/db
dmsetup remove skylocdb
losetup -d "$LOOP"
rm -f /tmp/disk.img

echo "2. the file system fills up: tmpfs of 48 KiB"
mkdir -p /mnt/small
mount -t tmpfs -o size=48k tmpfs /mnt/small || {
  bad "tmpfs mount failed"
  finish_scenario
}
ROUTE=/mnt/small/route.db
"$SKYLOC" teach --route "$ROUTE" --config "$CONFIG" --frames 1000 >/dev/null 2>/tmp/faults-full.err
rc=$?
expect_eq "teach exit status on a full file system" "$rc" 1
kept=$(sed -n 's/.*: \([0-9][0-9]*\) frames kept and committed.*/\1/p' /tmp/faults-full.err | head -n 1)
if [ -n "$kept" ]; then ok "teach kept and committed $kept frames"; else
  bad "teach did not commit what fitted"
  grep -v '^ *[a-z]* *[0-9]' /tmp/faults-full.err | sed 's/^/       | /' | tail -n 4
fi
if "$SKYLOC" route info "$ROUTE" >/tmp/faults-info.out 2>&1 && grep -q ", committed" /tmp/faults-info.out; then
  expect_eq "frames in the full-disk route" "$(frames_in /tmp/faults-info.out)" "$kept"
else
  bad "the full-disk route does not load: $(cat /tmp/faults-info.out)"
fi
umount /mnt/small
finish_scenario
