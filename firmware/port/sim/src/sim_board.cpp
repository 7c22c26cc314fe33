#include "flutterscan/firmware/sim/sim_board.hpp"

#include <cstring>

#include "flutterscan/common/sequencer.hpp"
#include "flutterscan/firmware/boot_decision.hpp"

namespace flutterscan::firmware::sim {

namespace {

using usb::DescriptorType;
using usb::StandardRequest;

constexpr std::uint8_t kGetDescriptor = static_cast<std::uint8_t>(StandardRequest::kGetDescriptor);

std::uint16_t descriptor_value(DescriptorType type, std::uint8_t index) {
  return static_cast<std::uint16_t>(static_cast<std::uint16_t>(type) << 8 | index);
}

/// ASCII of a UTF-16LE string descriptor ('?' outside ASCII).
std::string decode_string(const std::vector<std::uint8_t>& d) {
  std::string out;
  for (std::size_t i = 2; i + 1 < d.size() && i + 1 < d[0]; i += 2)
    out.push_back(d[i + 1] == 0 && d[i] < 0x80 ? static_cast<char>(d[i]) : '?');
  return out;
}

}  // namespace

std::vector<std::uint8_t> make_application_image(std::uint16_t board_id, std::uint8_t major,
                                                 std::uint8_t minor, std::uint8_t patch,
                                                 std::size_t size, std::uint32_t seed,
                                                 std::uint32_t load_address,
                                                 std::uint8_t security_version) {
  constexpr std::uint32_t kVectorOffset = 0x200;
  std::vector<std::uint8_t> image(std::max<std::size_t>(size, kVectorOffset + 16), 0);
  ImageHeader h{};
  h.security_version = security_version;
  h.magic = kImageMagic;
  h.header_version = kImageHeaderVersion;
  h.header_size = sizeof(ImageHeader);
  h.board_id = board_id;
  h.version_major = major;
  h.version_minor = minor;
  h.version_patch = patch;
  h.load_address = load_address;
  h.vector_table_offset = kVectorOffset;
  std::memcpy(image.data(), &h, sizeof h);
  std::uint32_t x = seed * 2654435761u + 1;
  for (std::size_t i = kVectorOffset; i < image.size(); ++i) {
    x = x * 1664525u + 1013904223u;
    image[i] = static_cast<std::uint8_t>(x >> 24);
  }
  // A vector table the bootloader accepts (check_boot_image): the initial SP
  // at the top of SRAM, the reset vector a Thumb address just after the table.
  const std::uint32_t sp = kSramEnd;
  const std::uint32_t reset = load_address + kVectorOffset + 8 + 1;
  std::memcpy(image.data() + kVectorOffset, &sp, sizeof sp);
  std::memcpy(image.data() + kVectorOffset + 4, &reset, sizeof reset);
  stamp_image(image);
  return image;
}

SimBoard::SimBoard(const SimBoardConfig& config, std::span<const std::uint8_t> initial_image)
    : config_(config), port_(config.board.pins) {
  if (!initial_image.empty()) flash_.load(config_.region.load_address, initial_image);
  boot(false);
}

SimBoard::~SimBoard() {
  teardown();
}

// ---------------------------------------------------------------------------
// Resets

void SimBoard::teardown() {
  if (usb_) usb_->attach(nullptr);
  application_.reset();
  handler_.reset();
  controller_.reset();
  bootloader_.reset();
  usb_.reset();
}

void SimBoard::boot(bool dfu_requested, ResetCause cause) {
  teardown();
  ++epoch_;
  // At reset the LED pins are inputs pulled low: every LED off.
  port_.write_led_bank(bsrr_all_off(config_.board.pins));
  usb_ = std::make_unique<SimUsbController>();
  confirmation_ = {};
  if (cause == ResetCause::kPowerOn) boot_record_ = {};  // SRAM lost
  const auto region_bytes = flash_.read(config_.region.load_address, config_.region.max_size);
  // The bootloader's decision (firmware/bootloader/src/startup.cpp).
  BootInputs in;
  in.dfu_requested = dfu_requested;
  in.boot_pin_held = recovery_pin_;
  in.watchdog_reset = cause == ResetCause::kWatchdog;  // RCC_CSR IWDGRSTF on the chip
  in.unconfirmed_starts = firmware::unconfirmed_starts(boot_record_);
  in.watchdog_resets = firmware::watchdog_resets(boot_record_);
  in.image = check_boot_image(region_bytes, config_.region, security_floor_.floor());
  const BootDecision decision = decide_boot(in);
  boot_record_ = make_boot_record(decision.unconfirmed_starts, decision.watchdog_resets);
  if (decision.target == BootTarget::kApplication) {
    const ImageHeader h = read_image_header(region_bytes);
    BoardConfig board = config_.board;
    board.firmware_major = h.version_major;
    board.firmware_minor = h.version_minor;
    board.firmware_patch = h.version_patch;
    board.build_id = h.image_crc32;
    device_descriptor_ = usb::application_device_descriptor(
        usb::bcd_device(h.version_major, h.version_minor, h.version_patch));
    port_.set_reset_cause(dfu_requested ? ResetCause::kSoftware : cause);
    controller_ = std::make_unique<Controller>(port_, board);
    handler_ = std::make_unique<CommandHandler>(*controller_);
    controller_->start();
    application_ = std::make_unique<usb::ApplicationUsb>(*usb_, *controller_, *handler_,
                                                         device_descriptor_, config_.unique_id);
    usb_->attach(application_.get());
    bootloader_entries_seen_ = port_.bootloader_entries();
    mode_ = BoardMode::kApplication;
  } else {
    device_descriptor_ = usb::bootloader_device_descriptor(usb::bcd_device(
        config_.bootloader_major, config_.bootloader_minor, config_.bootloader_patch));
    bootloader_ = std::make_unique<usb::BootloaderUsb>(*usb_, flash_, security_floor_,
                                                       kStm32f405Flash, config_.region,
                                                       device_descriptor_, config_.unique_id);
    usb_->attach(bootloader_.get());
    mode_ = BoardMode::kBootloader;
  }
}

void SimBoard::reset(bool dfu_requested) {
  boot(dfu_requested);
  if (reenumerate_callback_) reenumerate_callback_(mode_, epoch_);
}

void SimBoard::watchdog_reset() {
  boot(false, ResetCause::kWatchdog);
  if (reenumerate_callback_) reenumerate_callback_(mode_, epoch_);
}

void SimBoard::poll() {
  if (!application_) return;
  application_->poll();
  // The application's main loop (stm32f4 main.cpp): a host query answered over
  // configured USB, or USB configured long enough.
  if (confirmation_.poll(application_->device().configured(), handler_->queries_answered(),
                         port_.now_us())) {
    boot_record_ = confirm_boot_record(boot_record_);  // the watchdog count stays
    // This image works: no older one may run again (anti-rollback).
    const auto header = flash_.read(config_.region.load_address, sizeof(ImageHeader));
    security_floor_.raise(read_image_header(header).security_version);
  }
}

void SimBoard::after_host_call() {
  poll();
  bool dfu_requested = false;
  if (mode_ == BoardMode::kApplication) {
    if (port_.bootloader_entries() == bootloader_entries_seen_) return;
    dfu_requested = true;  // Port::enter_bootloader: hand-off word + reset
  } else if (!bootloader_ || !bootloader_->leave_requested()) {
    return;
  } else {
    boot_record_ = make_boot_record(0);  // a deliberate leave: new tries (bootloader main.cpp)
  }
  ++self_resets_;
  reset(dfu_requested);
}

void SimBoard::run_until(std::uint64_t time_us) {
  port_.run_until(time_us);
  after_host_call();
}

void SimBoard::run_for(std::uint64_t duration_us) {
  run_until(port_.now_us() + duration_us);
}

// ---------------------------------------------------------------------------
// Host side

ControlResult SimBoard::control_transfer(std::span<const std::uint8_t, 8> setup,
                                         std::span<const std::uint8_t> out_data) {
  ControlResult result = usb_->control_transfer(setup, out_data);
  after_host_call();
  return result;
}

ControlResult SimBoard::control_transfer(std::uint8_t request_type, std::uint8_t request,
                                         std::uint16_t value, std::uint16_t index,
                                         std::uint16_t length,
                                         std::span<const std::uint8_t> out_data) {
  ControlResult result =
      usb_->control_transfer(request_type, request, value, index, length, out_data);
  after_host_call();
  return result;
}

OutResult SimBoard::interrupt_out(std::uint8_t address, std::span<const std::uint8_t> packet) {
  const OutResult result = usb_->interrupt_out(address, packet);
  after_host_call();
  return result;
}

std::optional<std::vector<std::uint8_t>> SimBoard::interrupt_in(std::uint8_t address) {
  poll();  // events that became due since the last call
  auto packet = usb_->interrupt_in(address);
  after_host_call();
  return packet;
}

void SimBoard::bus_reset() {
  usb_->bus_reset();
  after_host_call();
}

Enumeration SimBoard::enumerate(std::uint8_t address) {
  Enumeration e;
  const std::uint32_t start_epoch = epoch_;
  auto step = [&](const char* what, std::uint8_t type, std::uint8_t request, std::uint16_t value,
                  std::uint16_t index, std::uint16_t length,
                  std::vector<std::uint8_t>* out) -> bool {
    if (!e.error.empty()) return false;
    const ControlResult r = control_transfer(type, request, value, index, length);
    if (r.stalled || epoch_ != start_epoch) {
      e.error = std::string(what) + (r.stalled ? ": STALL" : ": device reset");
      return false;
    }
    if (out != nullptr) *out = r.data;
    return true;
  };
  std::vector<std::uint8_t> scratch;
  // The hub debounces the connection for 100 ms before the first reset (USB
  // 2.0 7.1.7.3); the device runs meanwhile.
  run_for(kAttachDebounceUs);
  // hub_port_init: reset, 64-byte device descriptor read at address 0, reset, SET_ADDRESS.
  bus_reset();
  step("GET_DESCRIPTOR(device, 64) at address 0", 0x80, kGetDescriptor,
       descriptor_value(DescriptorType::kDevice, 0), 0, 64, &scratch);
  bus_reset();
  step("SET_ADDRESS", 0x00, static_cast<std::uint8_t>(StandardRequest::kSetAddress), address, 0, 0,
       nullptr);
  step("GET_DESCRIPTOR(device, 18)", 0x80, kGetDescriptor,
       descriptor_value(DescriptorType::kDevice, 0), 0, 18, &e.device_descriptor);
  if (e.error.empty() && e.device_descriptor.size() != 18) e.error = "device descriptor length";
  // usb_get_configuration: the 9-byte header, then wTotalLength bytes.
  step("GET_DESCRIPTOR(configuration, 9)", 0x80, kGetDescriptor,
       descriptor_value(DescriptorType::kConfiguration, 0), 0, 9, &scratch);
  if (e.error.empty() && scratch.size() != 9) e.error = "configuration header length";
  const std::uint16_t total =
      e.error.empty() ? static_cast<std::uint16_t>(scratch[2] | scratch[3] << 8) : 0;
  step("GET_DESCRIPTOR(configuration, total)", 0x80, kGetDescriptor,
       descriptor_value(DescriptorType::kConfiguration, 0), 0, total, &e.configuration_descriptor);
  if (e.error.empty() && e.configuration_descriptor.size() != total)
    e.error = "configuration descriptor shorter than wTotalLength";
  // Strings: language IDs, then product, manufacturer, serial in the first language.
  std::vector<std::uint8_t> langs;
  step("GET_DESCRIPTOR(string 0)", 0x80, kGetDescriptor,
       descriptor_value(DescriptorType::kString, 0), 0, 255, &langs);
  if (e.error.empty() && (langs.size() < 4 || langs[0] < 4)) e.error = "no language ID";
  if (e.error.empty()) {
    const std::uint16_t lang = static_cast<std::uint16_t>(langs[2] | langs[3] << 8);
    const std::uint8_t i_manufacturer = e.device_descriptor[14];
    const std::uint8_t i_product = e.device_descriptor[15];
    const std::uint8_t i_serial = e.device_descriptor[16];
    std::vector<std::uint8_t> s;
    if (step("GET_DESCRIPTOR(string iProduct)", 0x80, kGetDescriptor,
             descriptor_value(DescriptorType::kString, i_product), lang, 255, &s))
      e.product = decode_string(s);
    if (step("GET_DESCRIPTOR(string iManufacturer)", 0x80, kGetDescriptor,
             descriptor_value(DescriptorType::kString, i_manufacturer), lang, 255, &s))
      e.manufacturer = decode_string(s);
    if (step("GET_DESCRIPTOR(string iSerialNumber)", 0x80, kGetDescriptor,
             descriptor_value(DescriptorType::kString, i_serial), lang, 255, &s))
      e.serial = decode_string(s);
  }
  step("SET_CONFIGURATION(1)", 0x00, static_cast<std::uint8_t>(StandardRequest::kSetConfiguration),
       1, 0, 0, nullptr);
  if (e.error.empty() && mode_ == BoardMode::kApplication) {
    // usbhid: SET_IDLE(0) (a STALL is tolerated by Linux, not by this check),
    // then the report descriptor.
    step("HID SET_IDLE", 0x21, usb::kHidSetIdle, 0, usb::kHidInterface, 0, nullptr);
    step("GET_DESCRIPTOR(HID report)", 0x81, kGetDescriptor,
         descriptor_value(DescriptorType::kHidReport, 0), usb::kHidInterface,
         static_cast<std::uint16_t>(usb::kHidReportDescriptor.size()), &e.hid_report_descriptor);
  }
  e.ok = e.error.empty();
  return e;
}

// ---------------------------------------------------------------------------
// Identity

std::uint16_t SimBoard::vendor_id() const {
  return static_cast<std::uint16_t>(device_descriptor_[8] | device_descriptor_[9] << 8);
}

std::uint16_t SimBoard::product_id() const {
  return static_cast<std::uint16_t>(device_descriptor_[10] | device_descriptor_[11] << 8);
}

std::uint16_t SimBoard::bcd_device() const {
  return static_cast<std::uint16_t>(device_descriptor_[12] | device_descriptor_[13] << 8);
}

std::vector<std::uint8_t> SimBoard::sysfs_descriptors() const {
  std::vector<std::uint8_t> out(device_descriptor_.begin(), device_descriptor_.end());
  const std::span<const std::uint8_t> config =
      mode_ == BoardMode::kApplication
          ? std::span<const std::uint8_t>(usb::kApplicationConfiguration)
          : std::span<const std::uint8_t>(usb::kBootloaderConfiguration);
  out.insert(out.end(), config.begin(), config.end());
  return out;
}

std::span<const std::uint8_t> SimBoard::hid_report_descriptor() const {
  if (mode_ != BoardMode::kApplication) return {};
  return usb::kHidReportDescriptor;
}

std::string SimBoard::serial() const {
  const auto s = usb::serial_number(config_.unique_id);
  return std::string(s.begin(), s.end());
}

}  // namespace flutterscan::firmware::sim
