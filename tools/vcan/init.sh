#!/bin/busybox sh
# /init of the vcan guest's initramfs (built by tools/vcan/vcan-hil): loads the modules listed in
# /modules/order (virtio, 9p, CAN, vcan), mounts the host's root file system read-only (9p tag
# hostroot) and the harness's output directory read-write over its own path (tag out, path in
# $sdins_out from the kernel command line), then runs tools/vcan/guest.py on $sdins_out/job.json
# in a chroot of the host's root: the very binaries built on the host. Powers off at the end; the
# markers "vcan-guest: booted" and "vcan-guest: exit N" on the console tell the harness how far it got.
B=/bin/busybox
fail() {
  echo "vcan-guest: FAILED: $*"
  echo "vcan-guest: exit 1"
  $B sync
  $B poweroff -f
}
$B mount -t proc proc /proc
$B mount -t sysfs sysfs /sys
$B mount -t devtmpfs devtmpfs /dev
echo "vcan-guest: init on kernel $($B uname -r)"
for m in $($B cat /modules/order); do
  $B insmod "/modules/$m" || fail "insmod $m"
done
[ -n "$sdins_out" ] || fail "no sdins_out= on the kernel command line"
opts=trans=virtio,version=9p2000.L,msize=262144
$B mount -t 9p -o "$opts,ro,cache=loose" hostroot /host || fail "mount 9p hostroot"
$B mount -t proc proc /host/proc
$B mount -t sysfs sysfs /host/sys
$B mount -t devtmpfs devtmpfs /host/dev
$B mkdir -p /host/dev/shm
$B mount -t tmpfs tmpfs /host/dev/shm
# No tmpfs over /tmp: the build tree may be under it (CI's clean clone). Scratch: $sdins_out/tmp.
$B mount -t 9p -o "$opts" out "/host$sdins_out" || fail "mount 9p out on $sdins_out"
$B mkdir -p "/host$sdins_out/tmp"
$B ip link set lo up 2>/dev/null
echo "vcan-guest: booted ($($B cut -d' ' -f1 /proc/uptime) s since the kernel started)"
HOME=$sdins_out/tmp TMPDIR=$sdins_out/tmp PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin LANG=C.UTF-8 \
  $B chroot /host /usr/bin/python3 "$sdins_out/guest.py" "$sdins_out/job.json"
rc=$?
$B sync
echo "vcan-guest: exit $rc"
$B umount "/host$sdins_out"
$B poweroff -f
