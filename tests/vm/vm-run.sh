#!/usr/bin/env bash
# Run one host command inside a small QEMU VM whose kernel has SocketCAN, with vcan0 up.
#
#   tests/vm/vm-run.sh [--vm-dir DIR] [--timeout S] [--mem MB] -- CMD [ARG...]
#   tests/vm/vm-run.sh [--vm-dir DIR] --prepare
#
# This machine's kernel (and CI's) has no AF_CAN, so SocketCAN code runs in a guest:
#   * kernel + modules: Debian's linux-image-amd64 (its 6.1 dependency), fetched with
#     `apt-get download` and unpacked with `dpkg-deb -x` under the VM directory; nothing is
#     installed into the host's /boot.
#   * initramfs: busybox-static and the modules can, can-raw, can-dev, vcan and the virtio/9p
#     stack; /init creates vcan0, mounts the host's / read-only over virtio-9p, chroots into it
#     and runs CMD in the current directory with bash; /tmp shows the host's files, but what
#     the guest writes there stays in the guest (an overlay on a tmpfs).
#   * the exit status comes back twice: as the file rc in a writable 9p share (the run
#     directory, $DFP_VM_OUT inside the guest, for files the command wants to hand back) and as
#     the console line "DFP_VM_EXIT=<rc>"; then the guest does `reboot -f` and QEMU exits.
#   * qemu-system-x86_64 -accel tcg (no KVM), bounded by `timeout`.
# The prepared files are cached in the VM directory (default build/vm, never committed); a
# change of this script or of the kernel package rebuilds the initramfs.
#
# Exit status: CMD's, or 124 when the VM timed out, or 125 when the VM could not be prepared
# or gave no exit status. Needs qemu-system-x86, busybox-static, cpio (and apt-get with package
# lists for the first preparation).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
vm_dir="$repo/build/vm"
timeout_s=240
mem_mb=512
prepare_only=0

die() { echo "vm-run: $*" >&2; exit 125; }

while [ $# -gt 0 ]; do
  case "$1" in
    --vm-dir) vm_dir="$2"; shift 2 ;;
    --timeout) timeout_s="$2"; shift 2 ;;
    --mem) mem_mb="$2"; shift 2 ;;
    --prepare) prepare_only=1; shift ;;
    --) shift; break ;;
    -*) die "unknown option $1" ;;
    *) break ;;
  esac
done
[ "$prepare_only" = 1 ] || [ $# -gt 0 ] || die "usage: vm-run.sh [--vm-dir DIR] [--timeout S] -- CMD [ARG...]"


# Load order matters: the Debian .deb has no modules.dep, so dependencies come first.
MODULES="virtio_ring virtio virtio_pci_modern_dev virtio_pci_legacy_dev virtio_pci netfs fscache
9pnet 9pnet_virtio 9p overlay can can-raw can-dev vcan"

for tool in qemu-system-x86_64 cpio dpkg-deb timeout; do
  command -v "$tool" >/dev/null 2>&1 || die "$tool not found (apt-get install qemu-system-x86 cpio)"
done

write_init() {
  cat >"$1" <<'INIT'
#!/bin/busybox sh
/bin/busybox --install -s /bin
export PATH=/bin:/sbin
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev 2>/dev/null
for m in $(cat /modules.list); do
  insmod "/modules/$m.ko" || echo "DFP_VM: insmod $m failed"
done
ip link set up dev lo
ip link add dev vcan0 type vcan && ip link set up dev vcan0 || echo "DFP_VM: cannot create vcan0"
mkdir -p /host
opts=trans=virtio,version=9p2000.L,msize=262144
out=/host/run/dfp-vm
if mount -t 9p -o "$opts,ro,cache=loose" hostroot /host &&
   mount -t tmpfs run /host/run && mkdir -p $out && mount -t 9p -o "$opts" vmout $out; then
  mount -t proc proc /host/proc
  mount -t sysfs sys /host/sys
  mount -t devtmpfs dev /host/dev
  mkdir -p /host/dev/pts 2>/dev/null
  mount -t devpts -o ptmxmode=666 devpts /host/dev/pts
  # /tmp: the host's files stay visible, the guest's writes go to a tmpfs (overlay).
  mkdir -p /scratch && mount -t tmpfs scratch /scratch && mkdir -p /scratch/up /scratch/work
  mount -t overlay -o lowerdir=/host/tmp,upperdir=/scratch/up,workdir=/scratch/work tmp /host/tmp ||
    { echo "DFP_VM: no overlay for /tmp, using an empty tmpfs"; mount -t tmpfs tmp /host/tmp; }
  echo "DFP_VM_BOOTED uptime=$(cut -d' ' -f1 /proc/uptime)"
  chroot /host /bin/bash /run/dfp-vm/cmd.sh
  rc=$?
  echo "$rc" >$out/rc
  sync
else
  echo "DFP_VM: cannot mount the host's root over virtio-9p"
  rc=125
fi
echo "DFP_VM_EXIT=$rc"
reboot -f
INIT
  chmod +x "$1"
}

# The kernel package linux-image-amd64 points at (e.g. linux-image-6.1.0-56-amd64).
kernel_package() {
  apt-cache depends linux-image-amd64 2>/dev/null | awk '/Depends: linux-image-/ {print $2; exit}'
}

prepare() {
  mkdir -p "$vm_dir"
  local pkg
  pkg="$(kernel_package || true)"
  if [ -z "$pkg" ]; then
    if [ "$(id -u)" = 0 ]; then
      echo "vm-run: no package lists for linux-image-amd64, running apt-get update" >&2
      apt-get update -qq >&2 || die "apt-get update failed"
      pkg="$(kernel_package || true)"
    fi
    [ -n "$pkg" ] || die "apt-cache knows no linux-image-amd64 (run apt-get update as root)"
  fi
  local stamp
  stamp="$pkg $(sha256sum "${BASH_SOURCE[0]}" | cut -c1-16) $(sha256sum /bin/busybox 2>/dev/null | cut -c1-16)"
  if [ -f "$vm_dir/ready" ] && [ "$(cat "$vm_dir/ready")" = "$stamp" ] &&
     [ -f "$vm_dir/vmlinuz" ] && [ -f "$vm_dir/initrd.gz" ]; then
    return 0
  fi
  local t0=$SECONDS
  rm -f "$vm_dir/ready"
  if ! ls "$vm_dir/deb/$pkg"_*.deb >/dev/null 2>&1; then
    rm -rf "$vm_dir/deb" && mkdir -p "$vm_dir/deb"
    echo "vm-run: downloading $pkg" >&2
    if ! (cd "$vm_dir/deb" && apt-get download -q "$pkg" >&2); then
      # Stale package lists name a version the mirror no longer has.
      [ "$(id -u)" = 0 ] && apt-get update -qq >&2 &&
        (cd "$vm_dir/deb" && apt-get download -q "$pkg" >&2) ||
        die "apt-get download $pkg failed"
    fi
  fi
  rm -rf "$vm_dir/kernel"
  mkdir -p "$vm_dir/kernel"
  dpkg-deb -x "$vm_dir/deb/$pkg"_*.deb "$vm_dir/kernel"
  local vmlinuz
  vmlinuz="$(ls "$vm_dir"/kernel/boot/vmlinuz-* 2>/dev/null | head -n1)"
  [ -n "$vmlinuz" ] || die "$pkg has no boot/vmlinuz-*"
  [ -x /bin/busybox ] || die "/bin/busybox missing (apt-get install busybox-static)"
  if ldd /bin/busybox >/dev/null 2>&1; then
    die "/bin/busybox is dynamically linked (apt-get install busybox-static)"
  fi
  local ird="$vm_dir/initramfs"
  rm -rf "$ird"
  mkdir -p "$ird"/{bin,sbin,proc,sys,dev,host,modules,tmp}
  cp /bin/busybox "$ird/bin/busybox"
  local list=""
  for m in $MODULES; do
    local f
    f="$(find "$vm_dir/kernel/lib/modules" -name "$m.ko" -o -name "$m.ko.xz" -o -name "$m.ko.zst" | head -n1)"
    [ -n "$f" ] || die "module $m not in $pkg"
    case "$f" in
      *.ko) cp "$f" "$ird/modules/$m.ko" ;;
      *.xz) xz -dc "$f" >"$ird/modules/$m.ko" ;;
      *.zst) zstd -qdc "$f" >"$ird/modules/$m.ko" ;;
    esac
    list="$list $m"
  done
  echo "$list" >"$ird/modules.list"
  write_init "$ird/init"
  (cd "$ird" && find . | cpio -o -H newc --quiet | gzip -1) >"$vm_dir/initrd.gz.tmp"
  mv "$vm_dir/initrd.gz.tmp" "$vm_dir/initrd.gz"
  cp "$vmlinuz" "$vm_dir/vmlinuz"
  rm -rf "$vm_dir/kernel" "$ird" # 400 MB of unpacked modules; the .deb stays for the next build
  echo "$stamp" >"$vm_dir/ready"
  echo "vm-run: prepared $pkg in $((SECONDS - t0)) s under $vm_dir" >&2
}

mkdir -p "$vm_dir"
exec 9>"$vm_dir/.lock"
flock 9
prepare
flock -u 9
[ "$prepare_only" = 0 ] || exit 0

rundir="$(mktemp -d "$vm_dir/run.XXXXXX")"
trap 'rm -rf "$rundir"' EXIT
{
  echo "export PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin"
  echo "export HOME=/tmp TMPDIR=/tmp DFP_VM=1 DFP_VM_OUT=/run/dfp-vm"
  for v in ASAN_OPTIONS UBSAN_OPTIONS LSAN_OPTIONS; do
    if [ -n "${!v:-}" ]; then echo "export $v=$(printf %q "${!v}")"; fi
  done
  echo "cd $(printf %q "$PWD") || exit 125"
  printf '%q ' "$@"
  echo
} >"$rundir/cmd.sh"

t0=$(date +%s.%N)
set +e
timeout --kill-after=5 "$timeout_s" qemu-system-x86_64 -accel tcg -M pc -m "$mem_mb" \
  -display none -monitor none -serial stdio -no-reboot \
  -kernel "$vm_dir/vmlinuz" -initrd "$vm_dir/initrd.gz" \
  -append "console=ttyS0 quiet loglevel=3 panic=-1 reboot=t" \
  -virtfs local,path=/,mount_tag=hostroot,security_model=none,readonly=on,multidevs=remap \
  -virtfs "local,path=$rundir,mount_tag=vmout,security_model=none,multidevs=remap" \
  </dev/null 2>&1 | tr -d '\r' | tee "$rundir/console.log"
qrc=${PIPESTATUS[0]}
set -e
t1=$(date +%s.%N)
boot="$(sed -n 's/^DFP_VM_BOOTED uptime=//p' "$rundir/console.log" | head -n1)"
echo "vm-run: QEMU ran $(awk -v a="$t0" -v b="$t1" 'BEGIN {printf "%.1f", b - a}') s (guest booted in ${boot:-?} s)" >&2
if [ "$qrc" = 124 ] || [ "$qrc" = 137 ]; then
  echo "vm-run: the VM did not finish within $timeout_s s" >&2
  exit 124
fi
if [ -f "$rundir/rc" ]; then
  exit "$(cat "$rundir/rc")"
fi
rc="$(sed -n 's/^DFP_VM_EXIT=//p' "$rundir/console.log" | tail -n1)"
if [ -n "$rc" ]; then
  exit "$rc"
fi
echo "vm-run: no exit status from the VM (QEMU exit $qrc); console above" >&2
exit 125
