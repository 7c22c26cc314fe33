// The real bootloader ELF (build-fw-stm32f405) executed instruction by
// instruction in the Unicorn engine (label emu, issue 15 item 4, a first
// step): from the reset vector through Reset_Handler's decision
// (boot_decision.hpp) to either the application's reset handler (VTOR, MSP
// and the jump of start_application) or bootloader_main (DFU mode). The
// peripherals it touches on that path are modelled from RM0090 / PM0214:
// RCC_AHB1ENR, GPIOB MODER/PUPDR/IDR (the recovery pin PB2), SCB VTOR and
// CPACR. Any other access, to a peripheral or a register not modelled, fails
// the test loudly. Not modelled (so not reached): clocks, flash interface,
// OTG_FS, timers, DMA of the application; the emulation stops at the first
// instruction of the application or of bootloader_main.
// Skipped (exit 77 via GTEST_SKIP) without the built ELF and image.

#include <gtest/gtest.h>
#include <unicorn/unicorn.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include "flutterscan/common/crc32.hpp"
#include "flutterscan/common/image_header.hpp"
#include "flutterscan/firmware/boot_decision.hpp"

namespace flutterscan::firmware::emu {
namespace {

constexpr std::uint32_t kFlashBase = 0x08000000;
constexpr std::uint32_t kFlashSize = 1024 * 1024;
constexpr std::uint32_t kSramBase = 0x20000000;
constexpr std::uint32_t kSramSize = 128 * 1024;
constexpr std::uint32_t kAppBase = 0x08008000;
// RM0090 2.3 memory map, 7.3 RCC, 8.4 GPIO; PM0214 4.3 SCB.
constexpr std::uint32_t kRccBase = 0x40023800;
constexpr std::uint32_t kRccAhb1Enr = 0x30;
constexpr std::uint32_t kGpioBBase = 0x40020400;
constexpr std::uint32_t kGpioModer = 0x00;
constexpr std::uint32_t kGpioPupdr = 0x0C;
constexpr std::uint32_t kGpioIdr = 0x10;
constexpr std::uint32_t kScsBase = 0xE000E000;
constexpr std::uint32_t kScbVtor = 0xD08;
constexpr std::uint32_t kScbCpacr = 0xD88;

std::vector<std::uint8_t> read_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return {};
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

template <typename T>
T get(const std::vector<std::uint8_t>& b, std::size_t at) {
  T v{};
  if (at + sizeof v <= b.size()) std::memcpy(&v, b.data() + at, sizeof v);
  return v;
}

/// The loadable segments of a 32-bit little-endian ARM ELF (at their load
/// addresses) and one symbol's value.
struct Elf {
  struct Segment {
    std::uint32_t address;
    std::vector<std::uint8_t> bytes;
  };
  std::vector<Segment> segments;
  std::vector<std::uint8_t> file;

  static std::optional<Elf> load(const std::string& path) {
    Elf elf;
    elf.file = read_file(path);
    const auto& b = elf.file;
    if (b.size() < 52 ||
        std::memcmp(b.data(),
                    "\x7f"
                    "ELF",
                    4) != 0 ||
        b[4] != 1 || b[5] != 1)
      return std::nullopt;
    const auto phoff = get<std::uint32_t>(b, 28);
    const auto phentsize = get<std::uint16_t>(b, 42);
    const auto phnum = get<std::uint16_t>(b, 44);
    for (std::uint16_t i = 0; i < phnum; ++i) {
      const std::size_t ph = phoff + static_cast<std::size_t>(i) * phentsize;
      if (get<std::uint32_t>(b, ph) != 1) continue;  // PT_LOAD
      const auto offset = get<std::uint32_t>(b, ph + 4);
      const auto paddr = get<std::uint32_t>(b, ph + 12);
      const auto filesz = get<std::uint32_t>(b, ph + 16);
      if (filesz == 0 || offset + filesz > b.size()) continue;
      elf.segments.push_back(
          {paddr, std::vector<std::uint8_t>(b.begin() + offset, b.begin() + offset + filesz)});
    }
    return elf;
  }

  /// The value of symbol `name` (mangled), or 0.
  std::uint32_t symbol(const std::string& name) const {
    const auto& b = file;
    const auto shoff = get<std::uint32_t>(b, 32);
    const auto shentsize = get<std::uint16_t>(b, 46);
    const auto shnum = get<std::uint16_t>(b, 48);
    for (std::uint16_t i = 0; i < shnum; ++i) {
      const std::size_t sh = shoff + static_cast<std::size_t>(i) * shentsize;
      if (get<std::uint32_t>(b, sh + 4) != 2) continue;  // SHT_SYMTAB
      const auto offset = get<std::uint32_t>(b, sh + 16);
      const auto size = get<std::uint32_t>(b, sh + 20);
      const auto link = get<std::uint32_t>(b, sh + 24);
      const std::size_t strsh = shoff + static_cast<std::size_t>(link) * shentsize;
      const auto stroff = get<std::uint32_t>(b, strsh + 16);
      for (std::uint32_t s = 0; s + 16 <= size; s += 16) {
        const auto name_at = get<std::uint32_t>(b, offset + s);
        const char* n = reinterpret_cast<const char*>(b.data() + stroff + name_at);
        if (name == n) return get<std::uint32_t>(b, offset + s + 4);
      }
    }
    return 0;
  }
};

/// The chip: flash, SRAM, the modelled registers, and why it stopped.
class Chip {
 public:
  Chip() {
    EXPECT_EQ(uc_open(UC_ARCH_ARM, static_cast<uc_mode>(UC_MODE_THUMB | UC_MODE_MCLASS), &uc_),
              UC_ERR_OK);
    EXPECT_EQ(uc_ctl_set_cpu_model(uc_, UC_CPU_ARM_CORTEX_M4), UC_ERR_OK);
    EXPECT_EQ(uc_mem_map(uc_, kFlashBase, kFlashSize, UC_PROT_READ | UC_PROT_EXEC), UC_ERR_OK);
    EXPECT_EQ(uc_mem_map(uc_, kSramBase, kSramSize, UC_PROT_ALL), UC_ERR_OK);
    const std::vector<std::uint8_t> erased(kFlashSize, 0xFF);
    uc_mem_write(uc_, kFlashBase, erased.data(), erased.size());
    // SRAM after power-on: not zero, not a valid record.
    std::vector<std::uint8_t> sram(kSramSize);
    for (std::size_t i = 0; i < sram.size(); ++i) sram[i] = static_cast<std::uint8_t>(i * 37 + 11);
    uc_mem_write(uc_, kSramBase, sram.data(), sram.size());
    map_mmio(kRccBase, &Chip::rcc_read, &Chip::rcc_write);
    map_mmio(kGpioBBase, &Chip::gpiob_read, &Chip::gpiob_write);
    EXPECT_EQ(uc_mmio_map(uc_, kScsBase, 0x1000, &Chip::scs_read, this, &Chip::scs_write, this),
              UC_ERR_OK);
    uc_hook hook;
    uc_hook_add(uc_, &hook, UC_HOOK_MEM_UNMAPPED, reinterpret_cast<void*>(&Chip::unmapped), this, 1,
                0);
  }
  ~Chip() { uc_close(uc_); }
  Chip(const Chip&) = delete;
  Chip& operator=(const Chip&) = delete;

  void write(std::uint32_t address, const std::vector<std::uint8_t>& bytes) {
    ASSERT_EQ(uc_mem_write(uc_, address, bytes.data(), bytes.size()), UC_ERR_OK);
  }
  void write_word(std::uint32_t address, std::uint32_t value) {
    ASSERT_EQ(uc_mem_write(uc_, address, &value, 4), UC_ERR_OK);
  }
  std::uint32_t read_word(std::uint32_t address) {
    std::uint32_t v = 0;
    uc_mem_read(uc_, address, &v, 4);
    return v;
  }
  void stop_at(std::uint32_t address, const char* name) {
    stops_.push_back({address & ~1u, name});
    uc_hook hook;
    uc_hook_add(uc_, &hook, UC_HOOK_CODE, reinterpret_cast<void*>(&Chip::on_code), this,
                address & ~1u, address & ~1u);
  }

  /// Resets the core (SP and PC from the vector table at 0) and runs.
  std::string run() {
    const std::uint32_t sp = read_word(kFlashBase);
    const std::uint32_t pc = read_word(kFlashBase + 4);
    uc_reg_write(uc_, UC_ARM_REG_SP, &sp);
    const uc_err err = uc_emu_start(uc_, pc | 1u, 0, 0, 200'000'000);
    if (!error_.empty()) return "error: " + error_;
    if (err != UC_ERR_OK) return std::string("error: unicorn: ") + uc_strerror(err);
    return stopped_at_;
  }

  std::uint32_t reg(int r) {
    std::uint32_t v = 0;
    uc_reg_read(uc_, r, &v);
    return v;
  }

  bool recovery_pin_high = false;
  std::uint32_t rcc_ahb1enr = 0x00100000;  // reset value (CCMDATARAMEN)
  std::uint32_t gpiob_moder = 0x00000280;  // reset value of port B
  std::uint32_t gpiob_pupdr = 0x00000100;  // reset value of port B
  std::uint32_t vtor = 0;
  std::uint32_t cpacr = 0;

 private:
  using Read = std::uint64_t (*)(uc_engine*, std::uint64_t, unsigned, void*);
  using Write = void (*)(uc_engine*, std::uint64_t, unsigned, std::uint64_t, void*);

  void map_mmio(std::uint32_t base, Read on_read, Write on_write) {
    EXPECT_EQ(uc_mmio_map(uc_, base, 0x400, on_read, this, on_write, this), UC_ERR_OK);
  }
  void unmodelled(const char* what, std::uint64_t address) {
    char buffer[96];
    std::snprintf(buffer, sizeof buffer, "%s of 0x%08llx (not modelled)", what,
                  static_cast<unsigned long long>(address));
    if (error_.empty()) error_ = buffer;
    uc_emu_stop(uc_);
  }

  static std::uint64_t rcc_read(uc_engine*, std::uint64_t offset, unsigned size, void* user) {
    auto* chip = static_cast<Chip*>(user);
    if (offset == kRccAhb1Enr && size == 4) return chip->rcc_ahb1enr;
    chip->unmodelled("read", kRccBase + offset);
    return 0;
  }
  static void rcc_write(uc_engine*, std::uint64_t offset, unsigned size, std::uint64_t value,
                        void* user) {
    auto* chip = static_cast<Chip*>(user);
    if (offset == kRccAhb1Enr && size == 4) {
      chip->rcc_ahb1enr = static_cast<std::uint32_t>(value);
      return;
    }
    chip->unmodelled("write", kRccBase + offset);
  }
  bool gpiob_clocked() const { return (rcc_ahb1enr & (1u << 1)) != 0; }
  static std::uint64_t gpiob_read(uc_engine*, std::uint64_t offset, unsigned size, void* user) {
    auto* chip = static_cast<Chip*>(user);
    if (!chip->gpiob_clocked() || size != 4) {
      chip->unmodelled("read (port clock off)", kGpioBBase + offset);
      return 0;
    }
    switch (offset) {
      case kGpioModer:
        return chip->gpiob_moder;
      case kGpioPupdr:
        return chip->gpiob_pupdr;
      case kGpioIdr: {
        // PB2: the jumper to 3.3 V, else the board's pull-down (and the pin's own, if set).
        return chip->recovery_pin_high ? (1u << 2) : 0u;
      }
      default:
        chip->unmodelled("read", kGpioBBase + offset);
        return 0;
    }
  }
  static void gpiob_write(uc_engine*, std::uint64_t offset, unsigned size, std::uint64_t value,
                          void* user) {
    auto* chip = static_cast<Chip*>(user);
    if (!chip->gpiob_clocked() || size != 4) {
      chip->unmodelled("write (port clock off)", kGpioBBase + offset);
      return;
    }
    if (offset == kGpioPupdr) {
      chip->gpiob_pupdr = static_cast<std::uint32_t>(value);
    } else if (offset == kGpioModer) {
      chip->gpiob_moder = static_cast<std::uint32_t>(value);
    } else {
      chip->unmodelled("write", kGpioBBase + offset);
    }
  }
  static std::uint64_t scs_read(uc_engine*, std::uint64_t offset, unsigned, void* user) {
    auto* chip = static_cast<Chip*>(user);
    if (offset == kScbVtor) return chip->vtor;
    if (offset == kScbCpacr) return chip->cpacr;
    chip->unmodelled("read", kScsBase + offset);
    return 0;
  }
  static void scs_write(uc_engine*, std::uint64_t offset, unsigned, std::uint64_t value,
                        void* user) {
    auto* chip = static_cast<Chip*>(user);
    if (offset == kScbVtor) {
      chip->vtor = static_cast<std::uint32_t>(value);
    } else if (offset == kScbCpacr) {
      chip->cpacr = static_cast<std::uint32_t>(value);
    } else {
      chip->unmodelled("write", kScsBase + offset);
    }
  }
  static bool unmapped(uc_engine*, uc_mem_type type, std::uint64_t address, int, std::int64_t,
                       void* user) {
    static_cast<Chip*>(user)->unmodelled(type == UC_MEM_WRITE_UNMAPPED   ? "write"
                                         : type == UC_MEM_FETCH_UNMAPPED ? "fetch"
                                                                         : "read",
                                         address);
    return false;
  }
  static void on_code(uc_engine* uc, std::uint64_t address, std::uint32_t, void* user) {
    auto* chip = static_cast<Chip*>(user);
    for (const auto& [at, name] : chip->stops_)
      if (at == address) chip->stopped_at_ = name;
    uc_emu_stop(uc);
  }

  uc_engine* uc_ = nullptr;
  std::vector<std::pair<std::uint32_t, std::string>> stops_;
  std::string stopped_at_ = "no stop";
  std::string error_;
};

class BootloaderEmu : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto elf = Elf::load(FLUTTERSCAN_BOOTLOADER_ELF);
    image_ = read_file(FLUTTERSCAN_FW_STM32F405_BIN);
    if (!elf || image_.empty())
      GTEST_SKIP() << "no bootloader ELF / application image (make fw-stm32f405 builds them)";
    bootloader_ = *elf;
    bootloader_main_ = bootloader_.symbol("_Z15bootloader_mainv");
    ASSERT_NE(bootloader_main_, 0u);
    app_reset_ = get<std::uint32_t>(image_, kAppVectorTableOffset + 4);
    app_sp_ = get<std::uint32_t>(image_, kAppVectorTableOffset);
  }

  /// A chip with the bootloader and `app` in flash, stopping at the
  /// application's reset handler or at bootloader_main.
  void flash(Chip& chip, const std::vector<std::uint8_t>& app) {
    for (const auto& s : bootloader_.segments) chip.write(s.address, s.bytes);
    if (!app.empty()) chip.write(kAppBase, app);
    chip.stop_at(app_reset_, "application");
    chip.stop_at(bootloader_main_, "dfu");
  }

  Elf bootloader_;
  std::vector<std::uint8_t> image_;
  std::uint32_t bootloader_main_ = 0;
  std::uint32_t app_reset_ = 0;
  std::uint32_t app_sp_ = 0;
};

TEST_F(BootloaderEmu, AGoodImageIsStartedThroughItsVectorTable) {
  Chip chip;
  flash(chip, image_);
  ASSERT_EQ(chip.run(), "application");
  EXPECT_EQ(chip.reg(UC_ARM_REG_PC) | 1u, app_reset_);
  EXPECT_EQ(chip.reg(UC_ARM_REG_MSP), app_sp_);
  EXPECT_EQ(chip.vtor, kAppBase + kAppVectorTableOffset);
  // The recovery pin was read and everything put back as reset left it.
  EXPECT_EQ(chip.rcc_ahb1enr, 0x00100000u);
  EXPECT_EQ(chip.gpiob_pupdr, 0x00000100u);
  // This start is on trial: one unconfirmed start in the record.
  BootRecord record{};
  record.magic = chip.read_word(0x20000004);
  record.unconfirmed_starts = chip.read_word(0x20000008);
  record.check = chip.read_word(0x2000000C);
  EXPECT_EQ(unconfirmed_starts(record), 1u);
  EXPECT_EQ(chip.read_word(0x20000000), 0u);  // the hand-off word
}

TEST_F(BootloaderEmu, EmptyOrCorruptImagesStayInDfuMode) {
  {
    Chip chip;
    flash(chip, {});
    EXPECT_EQ(chip.run(), "dfu");
  }
  auto corrupt = image_;
  corrupt[corrupt.size() / 2] ^= 0x01;
  Chip chip;
  flash(chip, corrupt);
  EXPECT_EQ(chip.run(), "dfu");
}

TEST_F(BootloaderEmu, AResetVectorOutsideTheImageStaysInDfuMode) {
  auto image = image_;
  const std::uint32_t into_bootloader = 0x08000101;
  std::memcpy(image.data() + kAppVectorTableOffset + 4, &into_bootloader, 4);
  ASSERT_TRUE(stamp_image(image));  // CRC-valid
  Chip chip;
  flash(chip, image);
  EXPECT_EQ(chip.run(), "dfu");
}

TEST_F(BootloaderEmu, TheHandOffWordTheRecoveryPinAndUnconfirmedStartsKeepDfuMode) {
  {
    Chip chip;
    flash(chip, image_);
    chip.write_word(0x20000000, 0xB007DF11);  // EnterBootloader / DFU_DETACH
    EXPECT_EQ(chip.run(), "dfu");
    EXPECT_EQ(chip.read_word(0x20000000), 0u);  // once
  }
  {
    Chip chip;
    flash(chip, image_);
    chip.recovery_pin_high = true;
    EXPECT_EQ(chip.run(), "dfu");
  }
  for (std::uint32_t starts : {2u, 3u}) {
    Chip chip;
    flash(chip, image_);
    const BootRecord r = make_boot_record(starts);
    chip.write_word(0x20000004, r.magic);
    chip.write_word(0x20000008, r.unconfirmed_starts);
    chip.write_word(0x2000000C, r.check);
    EXPECT_EQ(chip.run(), starts < kMaxUnconfirmedStarts ? "application" : "dfu") << starts;
  }
}

}  // namespace
}  // namespace flutterscan::firmware::emu
