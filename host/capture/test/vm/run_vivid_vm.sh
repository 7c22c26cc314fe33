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
now_ms() { echo $(($(date +%s%N) / 1000000)); }
seconds_since() { local ms=$(($(now_ms) - $1)); printf "%d.%01d" $((ms / 1000)) $((ms % 1000 / 100)); }
started=$(now_ms)

say() { echo "vivid-vm: $*" >&2; }
fail() { say "FAIL: $*"; exit 1; }
skip() { echo "vivid-vm: SKIP: $*"; exit 77; }

[[ -x $check_program ]] || fail "check program $check_program missing or not executable"
if ! command -v qemu-system-x86_64 >/dev/null; then
  skip "qemu-system-x86_64 is not installed (run tools/install-deps: qemu-system-x86)"
fi
busybox=/bin/busybox
if ! "$busybox" --help >/dev/null 2>&1 || ldd "$busybox" >/dev/null 2>&1; then
  fail "$busybox is missing or not static (run tools/install-deps: busybox-static)"
fi
command -v cpio >/dev/null || fail "cpio is not installed (run tools/install-deps: cpio)"

# --- kernel and modules, cached ------------------------------------------------
here=$(dirname "$(realpath "$0")")
# shellcheck source=vm_kernel.sh
source "$here/vm_kernel.sh"
vm_kernel_prepare "$cache_dir"
say "kernel $VM_KERNEL_PACKAGE"

# --- initramfs -----------------------------------------------------------------
work=$(mktemp -d "$cache_dir/run.XXXXXX")
trap 'rm -rf "$work"' EXIT
root=$work/root
mkdir -p "$root"/{bin,dev,proc,sys,lib/modules}
cp "$busybox" "$root/bin/busybox"
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
log=$work/console.log
boot_started=$(now_ms)
set +e
timeout --kill-after=5 "$vm_timeout" qemu-system-x86_64 -accel tcg -m 512 -smp 1 \
  -nographic -no-reboot -monitor none \
  -kernel "$VM_KERNEL_DIR/vmlinuz" -initrd "$work/initramfs.cpio" \
  -append "console=ttyS0 panic=-1 quiet loglevel=3 rdinit=/init" \
  </dev/null >"$log" 2>"$work/qemu.err"
qemu_status=$?
set -e
boot_seconds=$(seconds_since "$boot_started")
tr -d '\r' <"$log" | sed 's/\x1b\[[0-9;?]*[a-zA-Z]//g' | grep -v '^\s*$' | sed 's/^/guest| /' >&2 || true

if ! grep -q 'guest: up' "$log"; then
  if ((qemu_status == 124 || qemu_status == 137)); then
    fail "the guest did not come up within ${vm_timeout} s"
  fi
  if grep -q -e 'SeaBIOS' -e 'Booting' -e 'Kernel panic' "$log"; then
    fail "QEMU ran (exit $qemu_status) but the guest's init never came up"
  fi
  skip "QEMU could not start (exit $qemu_status): $(head -c 400 "$work/qemu.err")"
fi
((qemu_status == 124 || qemu_status == 137)) && fail "the guest did not finish within ${vm_timeout} s"
grep -q 'V4L2-VM-DONE' "$log" || fail "the check program did not finish (no V4L2-VM-DONE line)"
results=$(tr -d '\r' <"$log" | grep '^V4L2-VM-RESULT' || true)
[[ -n $results ]] || fail "no V4L2-VM-RESULT line on the console"
echo "$results"
if grep -q 'FAIL' <<<"$results"; then
  fail "a capture check failed (see the lines above)"
fi
done_line=$(tr -d '\r' <"$log" | grep -m1 '^V4L2-VM-DONE')
[[ $done_line == "V4L2-VM-DONE rc=0 "* ]] || fail "the check program did not exit cleanly: $done_line"

total_seconds=$(seconds_since "$started")
echo "vivid-vm: PASS ($(grep -c PASS <<<"$results") capture runs; QEMU ${boot_seconds} s, total ${total_seconds} s)"
