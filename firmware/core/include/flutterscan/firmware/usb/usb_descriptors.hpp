#pragma once
// The device's descriptors, built at compile time: generic builders for the
// chapter 9, HID 1.11 and DFU 1.1 descriptors, and the two descriptor sets of
// the product: the application (HID + DFU runtime) and the bootloader (DFU
// mode). docs/protocol.md ("USB") lists them byte by byte; the USB contract
// shared with the host is there too. The serial number string is the only
// descriptor made at run time (from the chip's unique ID).
// Freestanding C++20: no heap, no exceptions, no RTTI.

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "flutterscan/common/dfu.hpp"
#include "flutterscan/common/protocol.hpp"
#include "flutterscan/firmware/usb/usb_types.hpp"

namespace flutterscan::firmware::usb {

// ---------------------------------------------------------------------------
// Builders

/// \brief `parts` one after the other.
template <std::size_t... N>
constexpr std::array<std::uint8_t, (N + ...)> concat(const std::array<std::uint8_t, N>&... parts) {
  std::array<std::uint8_t, (N + ...)> out{};
  std::size_t at = 0;
  ((std::copy_n(parts.begin(), N, out.begin() + static_cast<std::ptrdiff_t>(at)), at += N), ...);
  return out;
}

constexpr std::uint8_t lo(std::uint16_t v) {
  return static_cast<std::uint8_t>(v & 0xFF);
}
constexpr std::uint8_t hi(std::uint16_t v) {
  return static_cast<std::uint8_t>(v >> 8);
}

/// \brief bcdDevice from a firmware version: major (two BCD digits) in the high
/// byte, minor and patch (one BCD digit each, clamped to 9) in the low byte.
constexpr std::uint16_t bcd_device(int major, int minor, int patch) {
  const auto clamp9 = [](int v) { return v < 0 ? 0 : v > 9 ? 9 : v; };
  const int m = major < 0 ? 0 : major > 99 ? 99 : major;
  return static_cast<std::uint16_t>(((m / 10) << 12) | ((m % 10) << 8) | (clamp9(minor) << 4) |
                                    clamp9(patch));
}

/// \brief Device descriptor (USB 2.0 table 9-8): USB 2.0, class per interface, EP0 64 bytes.
constexpr std::array<std::uint8_t, 18> device_descriptor(
    std::uint16_t vendor_id, std::uint16_t product_id, std::uint16_t bcd,
    std::uint8_t i_manufacturer, std::uint8_t i_product, std::uint8_t i_serial) {
  return {18,
          static_cast<std::uint8_t>(DescriptorType::kDevice),
          0x00,
          0x02,  // bcdUSB 2.00
          0x00,
          0x00,
          0x00,  // class, subclass, protocol: per interface
          static_cast<std::uint8_t>(kEp0MaxPacket),
          lo(vendor_id),
          hi(vendor_id),
          lo(product_id),
          hi(product_id),
          lo(bcd),
          hi(bcd),
          i_manufacturer,
          i_product,
          i_serial,
          1};  // bNumConfigurations
}

/// \brief Configuration descriptor header (table 9-10); total length patched by
/// with_total_length().
constexpr std::array<std::uint8_t, 9> configuration_header(std::uint8_t interfaces,
                                                           std::uint8_t value,
                                                           std::uint8_t attributes,
                                                           std::uint16_t max_power_ma) {
  return {9,          static_cast<std::uint8_t>(DescriptorType::kConfiguration),
          0,          0,
          interfaces, value,
          0,  // iConfiguration
          attributes, static_cast<std::uint8_t>(max_power_ma / 2)};
}

/// \brief `config` with wTotalLength set to its size.
template <std::size_t N>
constexpr std::array<std::uint8_t, N> with_total_length(std::array<std::uint8_t, N> config) {
  static_assert(N <= 0xFFFF);
  config[2] = lo(static_cast<std::uint16_t>(N));
  config[3] = hi(static_cast<std::uint16_t>(N));
  return config;
}

/// \brief Interface descriptor (table 9-12).
constexpr std::array<std::uint8_t, 9> interface_descriptor(std::uint8_t number, std::uint8_t alt,
                                                           std::uint8_t endpoints, std::uint8_t cls,
                                                           std::uint8_t subclass,
                                                           std::uint8_t protocol,
                                                           std::uint8_t i_interface) {
  return {9,          static_cast<std::uint8_t>(DescriptorType::kInterface),
          number,     alt,
          endpoints,  cls,
          subclass,   protocol,
          i_interface};
}

/// \brief Endpoint descriptor (table 9-13).
constexpr std::array<std::uint8_t, 7> endpoint_descriptor(const EndpointConfig& ep,
                                                          std::uint8_t interval) {
  return {7,
          static_cast<std::uint8_t>(DescriptorType::kEndpoint),
          ep.address,
          static_cast<std::uint8_t>(ep.type),
          lo(ep.max_packet),
          hi(ep.max_packet),
          interval};
}

/// \brief HID descriptor (HID 1.11 6.2.1): HID 1.11, no country, one report descriptor.
constexpr std::array<std::uint8_t, 9> hid_descriptor(std::uint16_t report_descriptor_length) {
  return {9,
          static_cast<std::uint8_t>(DescriptorType::kHid),
          0x11,
          0x01,
          0,
          1,
          static_cast<std::uint8_t>(DescriptorType::kHidReport),
          lo(report_descriptor_length),
          hi(report_descriptor_length)};
}

/// \brief DFU functional descriptor (DFU 1.1 4.1.3).
constexpr std::array<std::uint8_t, 9> dfu_functional_descriptor(std::uint8_t attributes,
                                                                std::uint16_t detach_timeout_ms,
                                                                std::uint16_t transfer_size,
                                                                std::uint16_t bcd_dfu) {
  return {9,
          static_cast<std::uint8_t>(DescriptorType::kDfuFunctional),
          attributes,
          lo(detach_timeout_ms),
          hi(detach_timeout_ms),
          lo(transfer_size),
          hi(transfer_size),
          lo(bcd_dfu),
          hi(bcd_dfu)};
}

/// \brief String descriptor (table 9-16) of an ASCII literal, as UTF-16LE.
template <std::size_t N>
constexpr std::array<std::uint8_t, 2 + 2 * (N - 1)> string_descriptor(const char (&text)[N]) {
  static_assert(2 + 2 * (N - 1) <= 255, "string descriptor too long");
  std::array<std::uint8_t, 2 + 2 * (N - 1)> out{};
  out[0] = static_cast<std::uint8_t>(out.size());
  out[1] = static_cast<std::uint8_t>(DescriptorType::kString);
  for (std::size_t i = 0; i + 1 < N; ++i) out[2 + 2 * i] = static_cast<std::uint8_t>(text[i]);
  return out;
}

// ---------------------------------------------------------------------------
// Serial number: the chip's 96-bit unique ID as 24 upper-case hex digits

/// Bytes of the unique ID (STM32F4: 12 bytes at 0x1FFF7A10, RM0090 39.1).
inline constexpr std::size_t kUniqueIdSize = 12;
/// Characters of the serial number string.
inline constexpr std::size_t kSerialLength = 2 * kUniqueIdSize;

/// \brief The serial number: the unique ID's bytes in address order, each as
/// two upper-case hex digits (byte 0 first).
constexpr std::array<char, kSerialLength> serial_number(
    std::span<const std::uint8_t, kUniqueIdSize> unique_id) {
  constexpr char kHex[] = "0123456789ABCDEF";
  std::array<char, kSerialLength> out{};
  for (std::size_t i = 0; i < kUniqueIdSize; ++i) {
    out[2 * i] = kHex[unique_id[i] >> 4];
    out[2 * i + 1] = kHex[unique_id[i] & 0x0F];
  }
  return out;
}

/// \brief The serial number's string descriptor.
constexpr std::array<std::uint8_t, 2 + 2 * kSerialLength> serial_string_descriptor(
    std::span<const std::uint8_t, kUniqueIdSize> unique_id) {
  const auto serial = serial_number(unique_id);
  std::array<std::uint8_t, 2 + 2 * kSerialLength> out{};
  out[0] = static_cast<std::uint8_t>(out.size());
  out[1] = static_cast<std::uint8_t>(DescriptorType::kString);
  for (std::size_t i = 0; i < kSerialLength; ++i)
    out[2 + 2 * i] = static_cast<std::uint8_t>(serial[i]);
  return out;
}

// ---------------------------------------------------------------------------
// A device's descriptors as the device core serves them

/// \brief Everything UsbDevice answers GET_DESCRIPTOR with, and the endpoints it opens.
struct UsbDescriptorSet {
  std::span<const std::uint8_t> device;
  std::span<const std::uint8_t> configuration;  ///< the whole configuration (wTotalLength bytes)
  /// String descriptors by index (0: language IDs); the serial's entry is empty
  /// (UsbDevice serves the one made from the unique ID).
  std::span<const std::span<const std::uint8_t>> strings;
  std::uint8_t serial_index = 0;
  std::uint8_t interface_count = 0;
  std::uint8_t configuration_value = 1;
  /// The HID interface's number and its class and report descriptors (empty: no HID).
  std::uint8_t hid_interface = 0;
  std::span<const std::uint8_t> hid_descriptor;
  std::span<const std::uint8_t> hid_report_descriptor;
  std::span<const EndpointConfig> endpoints;  ///< opened by SET_CONFIGURATION
};

// ---------------------------------------------------------------------------
// The product's descriptors (the USB contract in docs/protocol.md)

// String indices.
inline constexpr std::uint8_t kStringManufacturer = 1;
inline constexpr std::uint8_t kStringProduct = 2;
inline constexpr std::uint8_t kStringSerial = 3;
inline constexpr std::uint8_t kStringDfuInterface = 4;

// HID interface.
inline constexpr std::uint8_t kHidInterface = 0;
inline constexpr EndpointConfig kHidInEndpoint{0x81, EndpointType::kInterrupt,
                                               protocol::kReportSize, kHidInterface};
inline constexpr EndpointConfig kHidOutEndpoint{0x01, EndpointType::kInterrupt,
                                                protocol::kReportSize, kHidInterface};
/// bInterval of both HID endpoints (1 ms frames at full speed).
inline constexpr std::uint8_t kHidInterval = 1;
/// DFU runtime interface of the application; the DFU mode interface of the bootloader is 0.
inline constexpr std::uint8_t kDfuRuntimeInterface = 1;
inline constexpr std::uint8_t kDfuModeInterface = 0;

/// Bus powered (bit 7 is reserved, set), no remote wakeup; 100 mA.
inline constexpr std::uint8_t kConfigurationAttributes = 0x80;
inline constexpr std::uint16_t kMaxPowerMa = 100;

/// Vendor-defined HID report descriptor: 64 bytes in, 64 bytes out, no report IDs.
inline constexpr std::array<std::uint8_t, 25> kHidReportDescriptor{
    0x06, 0x00, 0xFF,  // Usage Page (vendor 0xFF00)
    0x09, 0x01,        // Usage (1)
    0xA1, 0x01,        // Collection (Application)
    0x15, 0x00,        //   Logical Minimum (0)
    0x26, 0xFF, 0x00,  //   Logical Maximum (255)
    0x75, 0x08,        //   Report Size (8 bits)
    0x95, 0x40,        //   Report Count (64)
    0x09, 0x02,        //   Usage (2)
    0x81, 0x02,        //   Input (Data, Variable, Absolute): controller -> host
    0x09, 0x03,        //   Usage (3)
    0x91, 0x02,        //   Output (Data, Variable, Absolute): host -> controller
    0xC0,              // End Collection
};
static_assert(protocol::kReportSize == 0x40, "the report descriptor's Report Count");

inline constexpr auto kLanguageIds = std::array<std::uint8_t, 4>{
    4, static_cast<std::uint8_t>(DescriptorType::kString), 0x09, 0x04};  // en-US
inline constexpr auto kManufacturerString = string_descriptor("flutterscan");
inline constexpr auto kApplicationProductString = string_descriptor("flutterscan LED controller");
inline constexpr auto kBootloaderProductString = string_descriptor("flutterscan DFU bootloader");
inline constexpr auto kDfuInterfaceString = string_descriptor("Application flash");

// DFU functional descriptor values shared by both images (common/dfu.hpp).
inline constexpr auto kDfuFunctional =
    dfu_functional_descriptor(protocol::kDfuAttributes, protocol::kDfuDetachTimeoutMs,
                              protocol::kDfuTransferSize, protocol::kBcdDfu);
inline constexpr auto kHidClassDescriptor =
    hid_descriptor(static_cast<std::uint16_t>(kHidReportDescriptor.size()));

/// The application's configuration 1: HID (interface 0) + DFU runtime (interface 1).
inline constexpr auto kApplicationConfiguration = with_total_length(
    concat(configuration_header(2, 1, kConfigurationAttributes, kMaxPowerMa),
           interface_descriptor(kHidInterface, 0, 2, 0x03, 0x00, 0x00, 0), kHidClassDescriptor,
           endpoint_descriptor(kHidInEndpoint, kHidInterval),
           endpoint_descriptor(kHidOutEndpoint, kHidInterval),
           interface_descriptor(kDfuRuntimeInterface, 0, 0, protocol::kDfuInterfaceClass,
                                protocol::kDfuInterfaceSubclass, protocol::kDfuProtocolRuntime,
                                kStringDfuInterface),
           kDfuFunctional));
static_assert(kApplicationConfiguration.size() == 59);

/// The bootloader's configuration 1: one DFU mode interface.
inline constexpr auto kBootloaderConfiguration = with_total_length(
    concat(configuration_header(1, 1, kConfigurationAttributes, kMaxPowerMa),
           interface_descriptor(kDfuModeInterface, 0, 0, protocol::kDfuInterfaceClass,
                                protocol::kDfuInterfaceSubclass, protocol::kDfuProtocolDfuMode,
                                kStringDfuInterface),
           kDfuFunctional));
static_assert(kBootloaderConfiguration.size() == 27);

inline constexpr std::array<EndpointConfig, 2> kApplicationEndpoints{kHidInEndpoint,
                                                                     kHidOutEndpoint};

inline constexpr std::array<std::span<const std::uint8_t>, 5> kApplicationStrings{
    kLanguageIds, kManufacturerString, kApplicationProductString, {}, kDfuInterfaceString};
inline constexpr std::array<std::span<const std::uint8_t>, 5> kBootloaderStrings{
    kLanguageIds, kManufacturerString, kBootloaderProductString, {}, kDfuInterfaceString};

/// \brief The application's device descriptor (PID kUsbProductIdApplication).
constexpr std::array<std::uint8_t, 18> application_device_descriptor(std::uint16_t bcd) {
  return device_descriptor(protocol::kUsbVendorId, protocol::kUsbProductIdApplication, bcd,
                           kStringManufacturer, kStringProduct, kStringSerial);
}

/// \brief The bootloader's device descriptor (PID kUsbProductIdBootloader).
constexpr std::array<std::uint8_t, 18> bootloader_device_descriptor(std::uint16_t bcd) {
  return device_descriptor(protocol::kUsbVendorId, protocol::kUsbProductIdBootloader, bcd,
                           kStringManufacturer, kStringProduct, kStringSerial);
}

/// \brief The application's descriptor set around `device` (application_device_descriptor()).
constexpr UsbDescriptorSet application_descriptors(std::span<const std::uint8_t> device) {
  UsbDescriptorSet set;
  set.device = device;
  set.configuration = kApplicationConfiguration;
  set.strings = kApplicationStrings;
  set.serial_index = kStringSerial;
  set.interface_count = 2;
  set.hid_interface = kHidInterface;
  set.hid_descriptor = kHidClassDescriptor;
  set.hid_report_descriptor = kHidReportDescriptor;
  set.endpoints = kApplicationEndpoints;
  return set;
}

/// \brief The bootloader's descriptor set around `device` (bootloader_device_descriptor()).
constexpr UsbDescriptorSet bootloader_descriptors(std::span<const std::uint8_t> device) {
  UsbDescriptorSet set;
  set.device = device;
  set.configuration = kBootloaderConfiguration;
  set.strings = kBootloaderStrings;
  set.serial_index = kStringSerial;
  set.interface_count = 1;
  return set;
}

}  // namespace flutterscan::firmware::usb
