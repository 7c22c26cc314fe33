#include "flutterscan/firmware/config_store.hpp"

#include <cstring>

#include "flutterscan/firmware/crc32.hpp"

namespace flutterscan::firmware {
namespace {

using Loaded = Result<ControllerSettings, ConfigError>;

std::span<const std::uint8_t> bytes_of(const ConfigImage& image) {
  return {reinterpret_cast<const std::uint8_t*>(&image), sizeof(image)};
}

std::uint32_t image_crc(const ConfigImage& image) {
  return crc32(bytes_of(image).first(offsetof(ConfigImage, crc32)));
}

bool is_erased(std::span<const std::uint8_t> bytes) {
  for (const std::uint8_t b : bytes)
    if (b != 0xFF) return false;
  return true;
}

}  // namespace

ConfigImage encode_config(const ControllerSettings& settings) {
  ConfigImage image;
  std::memset(&image, 0, sizeof(image));
  image.magic = kConfigMagic;
  image.format_version = kConfigFormatVersion;
  image.image_size = sizeof(ConfigImage);
  image.selected_code = settings.selected_code;
  image.sync_mode = static_cast<std::uint8_t>(settings.mode.sync);
  image.strobe_active_low = settings.mode.strobe_active_low ? 1 : 0;
  image.slot_time_source = static_cast<std::uint8_t>(settings.timing.source);
  image.slot_time_us = settings.timing.slot_time_us;
  image.frame_period_us = settings.timing.frame_period_us;
  image.brightness_permille = settings.brightness_permille;
  image.max_on_time_us = settings.guard.max_on_time_us;
  image.max_duty_permille = settings.guard.max_duty_permille;
  for (std::size_t i = 0; i < settings.codes.size(); ++i) {
    const StoredCode& code = settings.codes[i];
    StoredCodeImage& out = image.codes[i];
    if (!code.present) continue;
    out.present = 1;
    out.leds = static_cast<std::uint8_t>(code.code.leds());
    out.length = static_cast<std::uint16_t>(code.code.length());
    for (int slot = 0; slot < code.code.length(); ++slot)
      out.masks[static_cast<std::size_t>(slot)] = code.code.mask(slot);
  }
  image.crc32 = image_crc(image);
  return image;
}

Loaded decode_config(std::span<const std::uint8_t> bytes, const BoardConfig& board) {
  if (bytes.size() < sizeof(ConfigImage)) return Loaded::failure(ConfigError::kBadSize);
  if (is_erased(bytes.first(sizeof(ConfigImage)))) return Loaded::failure(ConfigError::kEmpty);
  ConfigImage image;
  std::memcpy(&image, bytes.data(), sizeof(image));
  if (image.magic != kConfigMagic) return Loaded::failure(ConfigError::kBadMagic);
  if (image.format_version != kConfigFormatVersion)
    return Loaded::failure(ConfigError::kBadVersion);
  if (image.image_size != sizeof(ConfigImage)) return Loaded::failure(ConfigError::kBadSize);
  if (image.crc32 != image_crc(image)) return Loaded::failure(ConfigError::kCrcMismatch);

  // The same range checks as the commands: a valid CRC over bad values (an
  // image from another board, or a bug) must not reach the sequencer.
  const int led_count = board.pins.led_count;
  ControllerSettings settings = default_settings(board);
  protocol::SetTimingRequest timing_request{
      image.slot_time_us, image.frame_period_us, image.slot_time_source, {}};
  protocol::SetModeRequest mode_request{image.sync_mode, image.strobe_active_low, {}};
  const auto timing = timing_from_request(timing_request);
  const auto mode = mode_from_request(mode_request);
  if (!timing.ok() || !mode.ok()) return Loaded::failure(ConfigError::kBadContent);
  settings.timing = timing.value();
  settings.mode = mode.value();
  if (check_brightness(image.brightness_permille, led_count) != protocol::Status::kOk)
    return Loaded::failure(ConfigError::kBadContent);
  settings.brightness_permille = image.brightness_permille;
  settings.guard.max_on_time_us = image.max_on_time_us;
  settings.guard.max_duty_permille = image.max_duty_permille;
  if (check_guard_limits(settings.guard, led_count) != protocol::Status::kOk)
    return Loaded::failure(ConfigError::kBadContent);

  for (std::size_t i = 0; i < image.codes.size(); ++i) {
    const StoredCodeImage& in = image.codes[i];
    if (in.present == 0) continue;
    if (in.present != 1 || in.length > kMaxSlots) return Loaded::failure(ConfigError::kBadContent);
    const auto code =
        LedCode::from_masks(std::span<const std::uint8_t>(in.masks.data(), in.length), in.leds);
    if (!code.ok()) return Loaded::failure(ConfigError::kBadContent);
    settings.codes[i].present = true;
    settings.codes[i].code = code.value();
    if (check_stored_code(settings.codes[i], led_count) != protocol::Status::kOk)
      return Loaded::failure(ConfigError::kBadContent);
  }
  if (image.selected_code != protocol::kNoCode &&
      (image.selected_code >= protocol::kMaxCodes || !settings.codes[image.selected_code].present))
    return Loaded::failure(ConfigError::kBadContent);
  settings.selected_code = image.selected_code;
  return Loaded::success(settings);
}

Result<std::uint32_t, protocol::Status> save_config(Port& port,
                                                    const ControllerSettings& settings) {
  using Saved = Result<std::uint32_t, protocol::Status>;
  const ConfigImage image = encode_config(settings);
  if (port.config_page_size() < sizeof(ConfigImage))
    return Saved::failure(protocol::Status::kFlashError);
  if (port.erase_config_page() != PortStatus::kOk)
    return Saved::failure(protocol::Status::kFlashError);
  if (port.write_config_page(bytes_of(image)) != PortStatus::kOk)
    return Saved::failure(protocol::Status::kFlashError);
  ConfigImage readback;
  auto readback_bytes =
      std::span<std::uint8_t>(reinterpret_cast<std::uint8_t*>(&readback), sizeof(readback));
  if (port.read_config_page(readback_bytes) != PortStatus::kOk ||
      std::memcmp(&readback, &image, sizeof(image)) != 0)
    return Saved::failure(protocol::Status::kFlashError);
  return Saved::success(image.crc32);
}

Loaded load_config(Port& port, const BoardConfig& board) {
  ConfigImage image;
  auto bytes = std::span<std::uint8_t>(reinterpret_cast<std::uint8_t*>(&image), sizeof(image));
  if (port.config_page_size() < sizeof(ConfigImage) ||
      port.read_config_page(bytes) != PortStatus::kOk)
    return Loaded::failure(ConfigError::kReadFailed);
  return decode_config(bytes, board);
}

}  // namespace flutterscan::firmware
