#!/usr/bin/env bash
# The libcamera backend against the kernel's `vimc` test driver through libcamera's vimc pipeline
# handler, inside a QEMU guest (CTest label vm). The real flutterscan binary runs in the guest:
#   1. `flutterscan cameras` must list a libcamera camera (vimc's sensor, through the pipeline);
#   2. `flutterscan scan --camera libcamera:ID --controller sim --frames N` must capture N frames
#      through libcamera; the session folder it writes is checked on the host: N frames in
#      session.jsonl at the size asked for, sequence numbers increasing by one, camera
#      timestamps increasing, none lost, no camera error (none is processed: the sim controller
#      sees no strobe from a real camera, so no exposure event matches a frame);
#   3. CHECK_PROGRAM (libcamera_vimc_check, built from the backend's own sources) checks what the
#      scan does not show: the pixels, in both RGB orders, and refusals (its lines
#      LIBCAMERA-VM-RESULT NAME PASS|FAIL ...).
#
# The guest: the Debian kernel (vm_kernel.sh: fetched and cached as for run_vivid_vm.sh) with
# vimc.ko built once against it (also cached), a busybox-static initramfs that loads the media
# modules and vimc, and the host's / shared read-only over virtio 9p: init chroots into it, so
# flutterscan, its ~200 MB of shared libraries, libcamera and its IPA modules
# (/usr/lib/x86_64-linux-gnu/libcamera: ipa_vimc.so, signed, and vimc_ipa_proxy, from the
# libcamera-ipa package) are the host's own files, not copies. A second, writable 9p share
# receives the session folder. libcamera finds vimc's media device through libudev, which needs
# udev database entries: there is no udevd in the guest, so init writes them. The CPU is TCG's
# `max` model: flutterscan is built for x86-64-v3 (AVX2, FMA), which QEMU 7.2's TCG emulates.
#
# Usage: run_libcamera_vimc_vm.sh FLUTTERSCAN CHECK_PROGRAM CACHE_DIR [FRAMES]
#        run_libcamera_vimc_vm.sh --prepare CACHE_DIR   (only fetch the kernel and build vimc.ko:
#                                                        the ctest fixture before the guest test)
# Exit 0 pass, 1 fail, 77 skip (only when QEMU itself cannot start).
# Every wait is bounded: the guest gets VM_TIMEOUT seconds (default 200).
set -euo pipefail

prepare_only=false
if (($# == 2)) && [[ $1 == --prepare ]]; then
  prepare_only=true
  set -- - - "$2"
elif (($# < 3)); then
  echo "usage: $0 FLUTTERSCAN CHECK_PROGRAM CACHE_DIR [FRAMES] | $0 --prepare CACHE_DIR" >&2
  exit 2
fi
flutterscan=$(realpath -m "$1")
check_program=$(realpath -m "$2")
cache_dir=$(realpath -m "$3")
frames=${4:-8}
width=720
height=480
vm_timeout=${VM_TIMEOUT:-200}
here=$(dirname "$(realpath "$0")")
# Loaded in this order (each after the ones it depends on).
modules=(virtio_ring virtio virtio_pci_legacy_dev virtio_pci_modern_dev virtio_pci
  netfs fscache 9pnet 9pnet_virtio 9p
  mc videodev videobuf2-common videobuf2-v4l2 videobuf2-memops videobuf2-vmalloc
  videobuf2-dma-contig v4l2-tpg)
# shellcheck source=vm_kernel.sh
source "$here/vm_kernel.sh"
started=$(now_ms)

say() { echo "libcamera-vm: $*" >&2; }
fail() {
  say "FAIL: $*"
  exit 1
}
skip() {
  echo "libcamera-vm: SKIP: $*"
  exit 77
}

if $prepare_only; then
  vm_kernel_prepare "$cache_dir"
  vm_kernel_build_vimc
  echo "libcamera-vm: kernel $VM_KERNEL_PACKAGE ($VM_KERNEL_VERSION) and $VM_VIMC_KO ready" \
    "($(seconds_since "$started") s)"
  exit 0
fi
[[ -x $flutterscan ]] || fail "flutterscan binary $flutterscan missing or not executable"
[[ -x $check_program ]] || fail "check program $check_program missing or not executable"
if ! [[ $frames =~ ^[0-9]+$ ]] || ((frames < 2)); then fail "FRAMES must be a number >= 2"; fi
vm_guest_tools
command -v python3 >/dev/null || fail "python3 is not installed (run tools/install-deps: python3)"
ipa_dir=/usr/lib/x86_64-linux-gnu/libcamera
[[ -f $ipa_dir/ipa_vimc.so && -x $ipa_dir/vimc_ipa_proxy ]] ||
  fail "libcamera's vimc IPA module is not installed ($ipa_dir/ipa_vimc.so, vimc_ipa_proxy;" \
    "run tools/install-deps: libcamera-ipa)"
[[ $(ldd "$flutterscan") == *libcamera.so* ]] ||
  fail "$flutterscan is not linked with libcamera (configure with -DFLUTTERSCAN_LIBCAMERA=ON)"

# --- kernel, modules and vimc.ko, cached ------------------------------------------
vm_kernel_prepare "$cache_dir"
vm_kernel_build_vimc
say "kernel $VM_KERNEL_PACKAGE ($VM_KERNEL_VERSION), vimc $VM_VIMC_KO"

# --- initramfs -------------------------------------------------------------------
work=$(mktemp -d "$cache_dir/libcamera-run.XXXXXX")
trap 'rm -rf "$work"' EXIT
root=$work/root
out=$work/out
mkdir -p "$root"/{bin,dev,proc,sys,host,out,lib/modules} "$out"
cp /bin/busybox "$root/bin/busybox"
for m in "${modules[@]}"; do cp "$(vm_kernel_module "$m")" "$root/lib/modules/"; done
cp "$VM_VIMC_KO" "$root/lib/modules/"
# The session's camera settings: a small frame keeps the deblur of each frame short under TCG.
# libcamera 0.0.3's vimc pipeline aligns sizes to multiples of 6 (640x480 becomes 636x480, which
# the backend refuses as a size the pipeline changed).
cat >"$out/scan.toml" <<EOF
[camera]
width = $width
height = $height
EOF
# The guest's steps; each result line starts with LIBCAMERA-VM-. Inside the chroot the
# environment is clean but for what libcamera and flutterscan need; libcamera logs warnings.
{
  echo '#!/bin/busybox sh'
  echo '/bin/busybox --install -s /bin'
  echo 'mount -t proc proc /proc; mount -t sysfs sys /sys; mount -t devtmpfs dev /dev'
  echo 'echo "guest: up after $(cut -d" " -f1 /proc/uptime) s"'
  for m in "${modules[@]}" vimc; do
    echo "insmod /lib/modules/$m.ko || echo 'LIBCAMERA-VM-FAIL insmod $m failed'"
  done
  echo 'mount -t 9p -o trans=virtio,version=9p2000.L,ro,cache=loose hostroot /host ||
    echo "LIBCAMERA-VM-FAIL mounting the host root over 9p failed"'
  echo 'mount -t 9p -o trans=virtio,version=9p2000.L,cache=none out /out ||
    echo "LIBCAMERA-VM-FAIL mounting the output share over 9p failed"'
  echo 'mount -t proc proc /host/proc; mount -t sysfs sys /host/sys; mount -t devtmpfs dev /host/dev'
  echo 'mount -t tmpfs tmp /host/tmp; mount -t tmpfs run /host/run; mkdir -p /host/tmp/out'
  echo 'mount --bind /out /host/tmp/out'
  echo 'n=0; while [ ! -e /dev/media0 ] && [ $n -lt 50 ]; do sleep 0.2; n=$((n+1)); done'
  echo '[ -e /dev/media0 ] || echo "LIBCAMERA-VM-FAIL vimc made no /dev/media0"'
  # libcamera enumerates through libudev and takes only devices udev has initialised (that have
  # a database entry); without libudev it would read sysfs, but Debian's libcamera links it. No
  # udevd runs here: write the (empty) entries udevd would, for the media device and its nodes.
  echo 'mkdir -p /host/run/udev/data'
  echo 'for d in /sys/bus/media/devices/* /sys/class/video4linux/*; do'
  echo '  : >"/host/run/udev/data/c$(cat "$d/dev")"'
  echo 'done'
  echo 'echo "guest: modules loaded after $(cut -d" " -f1 /proc/uptime) s"'
  # A sanitizer build (host-asan) runs here too, with its options (the preset's LSan
  # suppressions).
  sanitizer_env=""
  for v in ASAN_OPTIONS LSAN_OPTIONS UBSAN_OPTIONS; do
    [[ -n ${!v:-} ]] && sanitizer_env+=" $(printf '%q' "$v=${!v}")"
  done
  printf 'run() { chroot /host /usr/bin/env -i HOME=/tmp PATH=/usr/bin:/bin LANG=C.UTF-8%s ' \
    "$sanitizer_env"
  printf 'LIBCAMERA_LOG_LEVELS=*:WARN %q "$@"; }\n' "$flutterscan"
  echo 't0=$(cut -d" " -f1 /proc/uptime)'
  echo 'run cameras >/out/cameras.txt 2>&1; echo "LIBCAMERA-VM-CAMERAS rc=$?"'
  echo 'echo "guest: cameras listed in $(cut -d" " -f1 /proc/uptime) s uptime (from $t0)"'
  echo 'sed "s/^/cameras| /" /out/cameras.txt'
  # The first libcamera spec listed: "  libcamera:ID  description" (IDs may hold spaces).
  echo "id=\$(sed -n 's/^  \\(libcamera:.*[^ ]\\)  .*\$/\\1/p' /out/cameras.txt | head -n 1)"
  echo 'if [ -n "$id" ]; then'
  echo '  echo "LIBCAMERA-VM-CAMERA $id"'
  printf '  run scan --config /tmp/out/scan.toml --camera "$id" --controller sim --frames %d ' "$frames"
  printf -- '--out /tmp/out/sessions '

  echo '--no-progress >/out/scan.txt 2>&1'
  echo '  echo "LIBCAMERA-VM-SCAN rc=$?"'
  echo '  sed "s/^/scan| /" /out/scan.txt | head -n 60'
  printf '  chroot /host /usr/bin/env -i%s LIBCAMERA_LOG_LEVELS=*:ERROR %q "$id" %d %d 10 ' \
    "$sanitizer_env" "$check_program" "$width" "$height"
  echo '>/out/check.txt 2>&1; echo "LIBCAMERA-VM-CHECK rc=$?"'
  echo '  cat /out/check.txt'
  echo 'fi'
  echo 'echo "LIBCAMERA-VM-DONE uptime=$(cut -d" " -f1 /proc/uptime)"'
  echo 'umount /host/tmp/out /out 2>/dev/null; sync'
  echo 'poweroff -f'
} >"$root/init"
chmod +x "$root/init"
(cd "$root" && find . | cpio -o -H newc --quiet >"$work/initramfs.cpio")

# --- boot ------------------------------------------------------------------------
# multidevs=remap: the host's /proc, /sys, /dev and /run are other file systems whose root
# directories share inode numbers; exported as they are, the guest takes them for one directory
# (proc mounted on /host/proc showed up on /host/sys, and the chroot had no /proc/self).
vm_boot "$work" "$vm_timeout" -cpu max -m 1024 \
  -virtfs local,path=/,mount_tag=hostroot,security_model=none,readonly=on,multidevs=remap \
  -virtfs local,path="$out",mount_tag=out,security_model=none
grep -q '^LIBCAMERA-VM-DONE' <<<"$VM_CONSOLE" || fail "the guest's steps did not finish (no DONE line)"
if grep '^LIBCAMERA-VM-FAIL' <<<"$VM_CONSOLE"; then fail "a guest step failed (see above)"; fi
grep -q '^LIBCAMERA-VM-CAMERAS rc=0$' <<<"$VM_CONSOLE" || fail "flutterscan cameras failed"
camera=$(sed -n 's/^LIBCAMERA-VM-CAMERA //p' <<<"$VM_CONSOLE" | head -n 1)
[[ -n $camera ]] || fail "flutterscan cameras listed no libcamera camera"
say "camera listed: $camera"
grep -q '^LIBCAMERA-VM-SCAN rc=0$' <<<"$VM_CONSOLE" || fail "flutterscan scan through $camera failed"

# --- the session folder ------------------------------------------------------------
session=$(find "$out/sessions" -mindepth 1 -maxdepth 1 -type d | head -n 1)
[[ -n $session ]] || fail "the scan wrote no session folder"
python3 "$here/check_libcamera_session.py" "$session" "$frames" "$width" "$height" ||
  fail "the session through $camera does not hold the frames asked for (see above)"

# --- the check program's lines ------------------------------------------------------
results=$(grep '^LIBCAMERA-VM-RESULT' <<<"$VM_CONSOLE" || true)
[[ -n $results ]] || fail "the check program printed no LIBCAMERA-VM-RESULT line"
echo "$results"
if grep -q ' FAIL ' <<<"$results"; then fail "a libcamera_vimc_check check failed (see above)"; fi
grep -q '^LIBCAMERA-VM-CHECK rc=0$' <<<"$VM_CONSOLE" || fail "libcamera_vimc_check did not exit 0"

total_seconds=$(seconds_since "$started")
echo "libcamera-vm: PASS ($camera: scan of $frames frames, $(grep -c ' PASS ' <<<"$results")" \
  "checks; QEMU ${VM_BOOT_SECONDS} s, total ${total_seconds} s)"
