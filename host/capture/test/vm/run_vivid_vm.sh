#!/usr/bin/env bash
# The v4l2 backend against the kernel's real `vivid` test driver, inside a
# QEMU guest (CTest label vm). Everything comes from Debian packages:
#   - the kernel and its media modules: `apt-get download linux-image-6.1.0-N-amd64`
#     (the version linux-image-amd64 points to), unpacked with dpkg-deb and
#     cached under CACHE_DIR, so only the first run downloads (~70 MB);
#   - busybox-static for the initramfs, qemu-system-x86 to boot it (TCG: KVM
#     hangs on this machine kind), cpio to pack it.
# The initramfs holds busybox, the modules rc-core cec mc videodev
# videobuf2-common videobuf2-v4l2 videobuf2-memops videobuf2-vmalloc
# videobuf2-dma-contig v4l2-dv-timings v4l2-tpg vivid (insmod'ed in that
# order), and CHECK_PROGRAM: the statically linked v4l2_vivid_check, built
# from the backend's own sources. The guest runs it, it prints one
# "V4L2-VM-RESULT io=<method> format=<fourcc> PASS|FAIL ..." line per I/O method on the serial
# console, and the guest powers off. This script passes when every line says
# PASS (by default RGB24 and SRGGB10, each with mmap and userptr) and the
# program exits 0.
#
# Usage: run_vivid_vm.sh CHECK_PROGRAM CACHE_DIR [check program options...]
# Exit 0 pass, 1 fail, 77 skip (only when QEMU itself cannot start).
# Every wait is bounded: the guest gets VM_TIMEOUT seconds (default 150).
set -euo pipefail

if (($# < 2)); then
  echo "usage: $0 CHECK_PROGRAM CACHE_DIR [check program options...]" >&2
  exit 2
fi
check_program=$(realpath -m "$1")
cache_dir=$(realpath -m "$2")
shift 2
guest_args=("$@")
vm_timeout=${VM_TIMEOUT:-150}
modules=(rc-core cec mc videodev videobuf2-common videobuf2-v4l2 videobuf2-memops
  videobuf2-vmalloc videobuf2-dma-contig v4l2-dv-timings v4l2-tpg vivid)
here=$(dirname "$(realpath "$0")")
# shellcheck source=vm_kernel.sh
source "$here/vm_kernel.sh"
started=$(now_ms)

say() { echo "vivid-vm: $*" >&2; }
fail() { say "FAIL: $*"; exit 1; }
skip() { echo "vivid-vm: SKIP: $*"; exit 77; }

[[ -x $check_program ]] || fail "check program $check_program missing or not executable"
vm_guest_tools

# --- kernel and modules, cached ------------------------------------------------
vm_kernel_prepare "$cache_dir"
say "kernel $VM_KERNEL_PACKAGE"

# --- initramfs -----------------------------------------------------------------
work=$(mktemp -d "$cache_dir/run.XXXXXX")
trap 'rm -rf "$work"' EXIT
root=$work/root
mkdir -p "$root"/{bin,dev,proc,sys,lib/modules}
cp /bin/busybox "$root/bin/busybox"
for m in "${modules[@]}"; do cp "$(vm_kernel_module "$m")" "$root/lib/modules/"; done
cp "$check_program" "$root/v4l2_vivid_check"
{
  echo '#!/bin/busybox sh'
  echo '/bin/busybox --install -s /bin'
  echo 'mount -t proc proc /proc; mount -t sysfs sys /sys; mount -t devtmpfs dev /dev'
  echo 'echo "guest: up after $(cut -d" " -f1 /proc/uptime) s"'
  for m in "${modules[@]}"; do
    params=""
    # One vivid instance with only its video capture node (/dev/video0).
    [[ $m == vivid ]] && params="n_devs=1 node_types=0x1"
    echo "insmod /lib/modules/$m.ko $params || echo 'V4L2-VM-RESULT io=all FAIL insmod $m failed'"
  done
  echo 'n=0; while [ ! -e /dev/video0 ] && [ $n -lt 50 ]; do sleep 0.2; n=$((n+1)); done'
  printf '/v4l2_vivid_check'
  ((${#guest_args[@]} == 0)) || printf ' %q' "${guest_args[@]}"
  echo
  echo 'echo "V4L2-VM-DONE rc=$? uptime=$(cut -d" " -f1 /proc/uptime)"'
  echo 'poweroff -f'
} >"$root/init"
chmod +x "$root/init"
(cd "$root" && find . | cpio -o -H newc --quiet >"$work/initramfs.cpio")

# --- boot ----------------------------------------------------------------------
vm_boot "$work" "$vm_timeout" -m 512
grep -q 'V4L2-VM-DONE' <<<"$VM_CONSOLE" || fail "the check program did not finish (no V4L2-VM-DONE line)"
results=$(grep '^V4L2-VM-RESULT' <<<"$VM_CONSOLE" || true)
[[ -n $results ]] || fail "no V4L2-VM-RESULT line on the console"
echo "$results"
if grep -q 'FAIL' <<<"$results"; then
  fail "a capture check failed (see the lines above)"
fi
done_line=$(grep -m1 '^V4L2-VM-DONE' <<<"$VM_CONSOLE")
[[ $done_line == "V4L2-VM-DONE rc=0 "* ]] || fail "the check program did not exit cleanly: $done_line"

total_seconds=$(seconds_since "$started")
echo "vivid-vm: PASS ($(grep -c PASS <<<"$results") capture runs; QEMU ${VM_BOOT_SECONDS} s, total ${total_seconds} s)"
