# Thin wrapper over CMake presets. The README's two commands are `make demo`
# and `make test`; `make bench` measures speed and search quality.
JOBS ?= $(shell nproc)
WERROR ?= $(if $(FLUTTERSCAN_WERROR),$(FLUTTERSCAN_WERROR),OFF)

.PHONY: all deps build test demo bench fuzz asan arm-common fw-qemu fw-stm32f405 format clean install

all: build

deps:
	@tools/install-deps

build: deps
	cmake --preset host-release -DFLUTTERSCAN_WERROR=$(WERROR) -DFLUTTERSCAN_TESTS=ON >/dev/null
	cmake --build --preset host-release -j $(JOBS)

arm-common: deps
	cmake --preset arm-common -DFLUTTERSCAN_WERROR=$(WERROR) >/dev/null
	cmake --build --preset arm-common -j $(JOBS)

fw-qemu: deps
	cmake --preset fw-qemu -DFLUTTERSCAN_WERROR=$(WERROR) >/dev/null
	cmake --build --preset fw-qemu -j $(JOBS)

fw-stm32f405: deps
	cmake --preset fw-stm32f405 -DFLUTTERSCAN_WERROR=$(WERROR) >/dev/null
	cmake --build --preset fw-stm32f405 -j $(JOBS)

test: build arm-common fw-qemu fw-stm32f405
	ctest --preset host-release -j $(JOBS)

# The binary, the controller firmware built with it (share/flutterscan/firmware)
# and the udev rules (/etc/udev/rules.d). PREFIX=/usr/local by default; DESTDIR stages.
PREFIX ?= /usr/local
install: build fw-stm32f405
	cmake --install build --prefix $(PREFIX)

# The first run on a fresh machine: only the product's packages and only the
# flutterscan target. A build tree already configured (say by `make test`) keeps
# its tests; a new one is configured without them.
demo:
	@tools/install-deps demo
	@test -f build/CMakeCache.txt || \
	  cmake --preset host-release -DFLUTTERSCAN_WERROR=$(WERROR) -DFLUTTERSCAN_TESTS=OFF >/dev/null
	cmake --build --preset host-release --target flutterscan -j $(JOBS)
	tools/demo

bench: build
	tools/bench

# libFuzzer: the firmware core (tools/fuzz, FUZZ_RUNS executions, default 10
# million), then every host target (tools/fuzz-host, host/fuzz/README.md;
# FUZZ_RUNS per target, default 1 million). `make test` replays the host corpora.
fuzz: deps
	tools/fuzz
	tools/fuzz-host

asan: deps
	cmake --preset host-asan -DFLUTTERSCAN_WERROR=$(WERROR) >/dev/null
	cmake --build --preset host-asan -j $(JOBS)
	ctest --preset host-asan -j $(JOBS)

format:
	git ls-files '*.cpp' '*.hpp' | xargs clang-format -i

clean:
	rm -rf build build-debug build-asan build-fuzz build-arm-common build-fw-qemu build-fw-stm32f405
