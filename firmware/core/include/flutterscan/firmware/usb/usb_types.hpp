#pragma once
// USB 2.0 chapter 9 vocabulary shared by the device core, its class
// interfaces and the device-controller drivers: the SETUP packet, request and
// descriptor codes, endpoint addresses. Numbers from the USB 2.0
// specification (tables 9-2 to 9-6) and the HID 1.11 and DFU 1.1 class specs.
// Freestanding C++20: no heap, no exceptions, no RTTI.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace flutterscan::firmware::usb {

/// Bytes of endpoint 0's packets (full speed: 8, 16, 32 or 64; this device: 64).
inline constexpr std::uint16_t kEp0MaxPacket = 64;

/// \brief An 8-byte SETUP packet, decoded (USB 2.0 table 9-2).
struct SetupPacket {
  std::uint8_t request_type = 0;  ///< bmRequestType
  std::uint8_t request = 0;       ///< bRequest
  std::uint16_t value = 0;        ///< wValue
  std::uint16_t index = 0;        ///< wIndex
  std::uint16_t length = 0;       ///< wLength

  /// \brief The packet as it arrives on the wire (little-endian fields).
  static constexpr SetupPacket parse(std::span<const std::uint8_t, 8> bytes) {
    return SetupPacket{bytes[0], bytes[1], static_cast<std::uint16_t>(bytes[2] | bytes[3] << 8),
                       static_cast<std::uint16_t>(bytes[4] | bytes[5] << 8),
                       static_cast<std::uint16_t>(bytes[6] | bytes[7] << 8)};
  }

  /// \brief The packet as it goes on the wire (the inverse of parse()).
  constexpr std::array<std::uint8_t, 8> bytes() const {
    return {request_type,
            request,
            static_cast<std::uint8_t>(value & 0xFF),
            static_cast<std::uint8_t>(value >> 8),
            static_cast<std::uint8_t>(index & 0xFF),
            static_cast<std::uint8_t>(index >> 8),
            static_cast<std::uint8_t>(length & 0xFF),
            static_cast<std::uint8_t>(length >> 8)};
  }

  /// \brief Device-to-host data stage (or no data stage with direction bit set).
  constexpr bool is_in() const { return (request_type & 0x80) != 0; }
  constexpr std::uint8_t type() const { return request_type & 0x60; }
  constexpr std::uint8_t recipient() const { return request_type & 0x1F; }
};

// bmRequestType fields.
inline constexpr std::uint8_t kRequestTypeStandard = 0x00;
inline constexpr std::uint8_t kRequestTypeClass = 0x20;
inline constexpr std::uint8_t kRequestTypeVendor = 0x40;
inline constexpr std::uint8_t kRecipientDevice = 0x00;
inline constexpr std::uint8_t kRecipientInterface = 0x01;
inline constexpr std::uint8_t kRecipientEndpoint = 0x02;

/// \brief Standard request codes (USB 2.0 table 9-4).
enum class StandardRequest : std::uint8_t {
  kGetStatus = 0,
  kClearFeature = 1,
  kSetFeature = 3,
  kSetAddress = 5,
  kGetDescriptor = 6,
  kSetDescriptor = 7,
  kGetConfiguration = 8,
  kSetConfiguration = 9,
  kGetInterface = 10,
  kSetInterface = 11,
  kSynchFrame = 12,
};

/// Feature selectors (USB 2.0 table 9-6).
inline constexpr std::uint16_t kFeatureEndpointHalt = 0;
inline constexpr std::uint16_t kFeatureDeviceRemoteWakeup = 1;
inline constexpr std::uint16_t kFeatureTestMode = 2;

/// \brief Descriptor types (USB 2.0 table 9-5; HID 1.11 7.1; DFU 1.1 4.1.3).
enum class DescriptorType : std::uint8_t {
  kDevice = 1,
  kConfiguration = 2,
  kString = 3,
  kInterface = 4,
  kEndpoint = 5,
  kDeviceQualifier = 6,
  kHid = 0x21,
  kHidReport = 0x22,
  kDfuFunctional = 0x21,  ///< same number as HID's, told apart by the interface class
};

/// \brief Transfer type of an endpoint (bmAttributes bits 1..0).
enum class EndpointType : std::uint8_t {
  kControl = 0,
  kIsochronous = 1,
  kBulk = 2,
  kInterrupt = 3
};

/// \brief True for an IN (device-to-host) endpoint address.
constexpr bool is_in_endpoint(std::uint8_t address) {
  return (address & 0x80) != 0;
}
/// \brief The endpoint number (0..15) of an endpoint address.
constexpr std::uint8_t endpoint_number(std::uint8_t address) {
  return address & 0x0F;
}

/// \brief An endpoint the configuration opens (besides endpoint 0).
struct EndpointConfig {
  std::uint8_t address = 0;  ///< bEndpointAddress (bit 7: IN)
  EndpointType type = EndpointType::kInterrupt;
  std::uint16_t max_packet = 0;
  std::uint8_t interface = 0;  ///< the interface that owns it
};

}  // namespace flutterscan::firmware::usb
