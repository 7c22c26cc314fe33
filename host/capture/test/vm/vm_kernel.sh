# Sourced by the QEMU guest tests (run_vivid_vm.sh, run_libcamera_vimc_vm.sh): the Debian kernel
# they boot, fetched once into a cache folder, and the vimc test driver built once against it.
#
#   vm_kernel_prepare CACHE_DIR   sets VM_KERNEL_DIR (vmlinuz, modules/...), VM_KERNEL_PACKAGE
#                                 (linux-image-6.1.0-N-amd64), VM_KERNEL_VERSION (its Debian
#                                 version, e.g. 6.1.192-2) and VM_KERNEL_RELEASE (6.1.0-N-amd64)
#   vm_kernel_module NAME         prints the path of module NAME (.ko) in that cache
#   vm_kernel_build_vimc          sets VM_VIMC_KO, the path of vimc.ko, building it on the first call
#   vm_guest_tools                checks QEMU (skips without it), busybox-static and cpio
#   vm_boot WORK TIMEOUT [QEMU OPTION...]
#                                 boots that kernel with WORK/initramfs.cpio under TCG, one CPU,
#                                 for at most TIMEOUT s; the console goes to stderr as "guest| "
#                                 lines and into VM_CONSOLE (carriage returns removed), the boot's
#                                 time into VM_BOOT_SECONDS. A guest whose init never ran fails
#                                 (or skips when QEMU itself could not start), as does one that
#                                 did not power off in time.
#   now_ms, seconds_since MS      the clock both use
#
# The kernel is the package linux-image-amd64 depends on, fetched with `apt-get download` (no
# root needed) and unpacked with dpkg-deb: vmlinuz and the module folders the tests load from
# (media, virtio, 9p). Debian's kernel does not build vimc (CONFIG_VIDEO_VIMC is not set), so
# vm_kernel_build_vimc fetches the same version's linux-source-6.1 (its tarball, ~140 MB, of
# which only drivers/media/test-drivers/vimc is unpacked), linux-headers-<release>, its -common
# part and linux-kbuild-6.1, all pinned to the image's exact Debian version so the module's
# vermagic and symbol versions match (the source and kbuild, where apt no longer has that
# version, at the newest Debian revision of the same kernel release: vm_kernel_package_version),
# and builds vimc.ko out of tree with gcc-12 (what the
# headers name; `g++` brings it). The module is unsigned: the guest boots without EFI secure
# boot, so there is no lockdown, and the kernel loads it with a taint. Everything is kept in
# CACHE_DIR/linux-image-<release>/ (vimc.ko under vimc/); downloads and sources are removed.
# A lock file serialises tests sharing the cache (ctest -j).
#
# Callers define say(), fail() and skip() (fail exits 1, skip 77). The guest's init prints
# "guest: up" first.

vm_kernel_module_trees=(drivers/media drivers/virtio fs/9p fs/netfs fs/fscache net/9p)

vm_kernel_lock() {
  exec {vm_kernel_lock_fd}>"$1/kernel.lock"
  flock -w 900 "$vm_kernel_lock_fd" || fail "waited 900 s for $1/kernel.lock"
}

vm_kernel_unlock() {
  flock -u "$vm_kernel_lock_fd"
  exec {vm_kernel_lock_fd}>&-
}

vm_kernel_prepare() {
  local cache_dir dir package download
  cache_dir=$(realpath -m "$1")
  mkdir -p "$cache_dir"
  vm_kernel_lock "$cache_dir"
  VM_KERNEL_DIR=""
  for dir in "$cache_dir"/linux-image-*; do
    [[ -f $dir/complete.2 ]] && VM_KERNEL_DIR=$dir
  done
  if [[ -z $VM_KERNEL_DIR ]]; then
    package=$(apt-cache depends linux-image-amd64 2>/dev/null |
      awk '/Depends: linux-image-6\.1\.0-[0-9]+-amd64$/ {print $2; exit}')
    [[ -n $package ]] || package=$(apt-cache search --names-only '^linux-image-6\.1\.0-[0-9]+-amd64$' |
      awk '{print $1}' | sort -V | tail -n 1)
    [[ -n $package ]] || fail "no linux-image-6.1.0-*-amd64 package known to apt (apt-get update?)"
    say "fetching $package (first run only)"
    rm -rf "$cache_dir"/download.* # left by a failed fetch (the lock is held: none is running)
    download=$(mktemp -d "$cache_dir/download.XXXXXX")
    (cd "$download" && timeout 300 apt-get download "$package" >/dev/null 2>"$download/apt.log") ||
      fail "apt-get download $package failed: $(tail -n 3 "$download/apt.log")"
    mkdir "$download/x"
    local patterns=('./boot/vmlinuz-*') tree
    for tree in "${vm_kernel_module_trees[@]}"; do patterns+=("./lib/modules/*/kernel/$tree/*"); done
    dpkg-deb --fsys-tarfile "$download"/*.deb | tar -x -C "$download/x" --wildcards "${patterns[@]}" ||
      fail "unpacking $package failed"
    VM_KERNEL_DIR=$cache_dir/$package
    rm -rf "$VM_KERNEL_DIR"
    mkdir -p "$VM_KERNEL_DIR"
    cp "$download"/x/boot/vmlinuz-* "$VM_KERNEL_DIR/vmlinuz"
    mv "$download"/x/lib/modules/*/kernel "$VM_KERNEL_DIR/modules"
    find "$VM_KERNEL_DIR/modules" -name '*.ko.xz' -exec xz -d {} +
    dpkg-deb -f "$download"/*.deb Version >"$VM_KERNEL_DIR/version"
    echo "${package#linux-image-}" >"$VM_KERNEL_DIR/release"
    rm -rf "$download"
    touch "$VM_KERNEL_DIR/complete.2"
  fi
  vm_kernel_unlock
  VM_KERNEL_PACKAGE=$(basename "$VM_KERNEL_DIR")
  VM_KERNEL_VERSION=$(cat "$VM_KERNEL_DIR/version")
  VM_KERNEL_RELEASE=$(cat "$VM_KERNEL_DIR/release")
}

vm_kernel_module() {
  local found
  found=$(find "$VM_KERNEL_DIR/modules" -name "$1.ko" | head -n 1)
  [[ -n $found ]] || fail "module $1 not found in $VM_KERNEL_PACKAGE"
  echo "$found"
}

# The version of NAME to build the image's modules with: the image's own Debian version where apt
# has it, else the newest of the same kernel release (6.1.192-3 for 6.1.192-2: the archive
# replaces a source or build-tools package by a new Debian revision of the same kernel, and
# drops the old one, while the image and its headers stay: seen on 2026-11-29 with
# linux-kbuild-6.1). The headers carry the symbol versions and vermagic; the source and the
# build tools of one kernel release build the same module.
vm_kernel_package_version() {
  local name=$1 versions
  versions=$(apt-cache madison "$name" 2>/dev/null | awk -F'|' '{gsub(/ /, "", $2); print $2}')
  if grep -qxF "$VM_KERNEL_VERSION" <<<"$versions"; then
    echo "$VM_KERNEL_VERSION"
    return
  fi
  local same
  same=$(awk -v p="${VM_KERNEL_VERSION%-*}-" 'index($0, p) == 1' <<<"$versions" | sort -V | tail -n 1)
  echo "${same:-$VM_KERNEL_VERSION}"
}

vm_kernel_build_vimc() {
  local cache_dir out build log pkg packages started
  cache_dir=$(dirname "$VM_KERNEL_DIR")
  out=$VM_KERNEL_DIR/vimc
  vm_kernel_lock "$cache_dir"
  if [[ ! -f $out/complete ]]; then
    started=$(date +%s)
    command -v gcc-12 >/dev/null || fail "gcc-12 is not installed (run tools/install-deps: g++)"
    command -v make >/dev/null || fail "make is not installed (run tools/install-deps: make)"
    command -v xz >/dev/null || fail "xz is not installed (run tools/install-deps: xz-utils)"
    packages=("linux-source-6.1=$(vm_kernel_package_version linux-source-6.1)"
      "linux-headers-$VM_KERNEL_RELEASE=$VM_KERNEL_VERSION"
      "linux-headers-${VM_KERNEL_RELEASE%-amd64}-common=$VM_KERNEL_VERSION"
      "linux-kbuild-6.1=$(vm_kernel_package_version linux-kbuild-6.1)")
    say "building vimc.ko for $VM_KERNEL_RELEASE from ${packages[*]} (first run only)"
    rm -rf "$cache_dir"/vimc-build.* # left by a failed build
    build=$(mktemp -d "$cache_dir/vimc-build.XXXXXX")
    log=$build/log
    (cd "$build" && timeout 600 apt-get download "${packages[@]}" >"$log" 2>&1) ||
      fail "apt-get download ${packages[*]} failed (if apt no longer has that version, delete" \
        "$cache_dir to fetch the current kernel): $(tail -n 3 "$log")"
    mkdir "$build/x"
    for pkg in "$build"/linux-headers-*.deb "$build"/linux-kbuild-*.deb; do
      dpkg-deb -x "$pkg" "$build/x" || fail "unpacking $pkg failed"
    done
    # The -amd64 headers include the -common ones by absolute path: point it at the copy here.
    local headers=$build/x/usr/src/linux-headers-$VM_KERNEL_RELEASE
    sed -i "s|^include /usr/src/|include $build/x/usr/src/|" "$headers/Makefile"
    dpkg-deb --fsys-tarfile "$build"/linux-source-6.1_*.deb |
      tar -x -O ./usr/src/linux-source-6.1.tar.xz | xz -dc |
      tar -x -C "$build" --wildcards 'linux-source-6.1/drivers/media/test-drivers/vimc/*' ||
      fail "unpacking vimc's source from linux-source-6.1 failed"
    local src=$build/linux-source-6.1/drivers/media/test-drivers/vimc
    make -C "$headers" M="$src" CONFIG_VIDEO_VIMC=m modules -j2 >>"$log" 2>&1 ||
      fail "building vimc.ko failed: $(tail -n 15 "$log")"
    grep -q "vermagic=$VM_KERNEL_RELEASE " <(strings "$src/vimc.ko") ||
      fail "vimc.ko was built for another kernel than $VM_KERNEL_RELEASE"
    rm -rf "$out"
    mkdir -p "$out"
    cp "$src/vimc.ko" "$out/"
    rm -rf "$build"
    touch "$out/complete"
    say "vimc.ko built in $(($(date +%s) - started)) s"
  fi
  vm_kernel_unlock
  VM_VIMC_KO=$out/vimc.ko
}

now_ms() { echo $(($(date +%s%N) / 1000000)); }
seconds_since() {
  local ms=$(($(now_ms) - $1))
  printf "%d.%01d" $((ms / 1000)) $((ms % 1000 / 100))
}

vm_guest_tools() {
  if ! command -v qemu-system-x86_64 >/dev/null; then
    skip "qemu-system-x86_64 is not installed (run tools/install-deps: qemu-system-x86)"
  fi
  if ! /bin/busybox --help >/dev/null 2>&1 || ldd /bin/busybox >/dev/null 2>&1; then
    fail "/bin/busybox is missing or not static (run tools/install-deps: busybox-static)"
  fi
  command -v cpio >/dev/null || fail "cpio is not installed (run tools/install-deps: cpio)"
}

vm_boot() {
  local work=$1 timeout_s=$2 started status
  shift 2
  started=$(now_ms)
  set +e
  timeout --kill-after=5 "$timeout_s" qemu-system-x86_64 -accel tcg -smp 1 \
    -nographic -no-reboot -monitor none \
    -kernel "$VM_KERNEL_DIR/vmlinuz" -initrd "$work/initramfs.cpio" \
    -append "console=ttyS0 panic=-1 quiet loglevel=3 rdinit=/init" "$@" \
    </dev/null >"$work/console.log" 2>"$work/qemu.err"
  status=$?
  set -e
  VM_BOOT_SECONDS=$(seconds_since "$started")
  VM_CONSOLE=$(tr -d '\r' <"$work/console.log")
  sed 's/\x1b\[[0-9;?]*[a-zA-Z]//g' <<<"$VM_CONSOLE" | grep -v '^\s*$' | sed 's/^/guest| /' >&2 || true
  if ! grep -q 'guest: up' <<<"$VM_CONSOLE"; then
    if ((status == 124 || status == 137)); then
      fail "the guest did not come up within ${timeout_s} s"
    fi
    if grep -q -e 'SeaBIOS' -e 'Booting' -e 'Kernel panic' <<<"$VM_CONSOLE"; then
      fail "QEMU ran (exit $status) but the guest's init never came up"
    fi
    skip "QEMU could not start (exit $status): $(head -c 400 "$work/qemu.err")"
  fi
  if ((status == 124 || status == 137)); then fail "the guest did not finish within ${timeout_s} s"; fi
}
