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

// Not inlined: the fuzz build leaves this byte loop uninstrumented by name
// (firmware/fuzz/coverage_ignorelist.txt), which works only for a function of its own.
[[gnu::noinline]] bool is_erased(std::span<const std::uint8_t> bytes) {
  const std::uint8_t* p = bytes.data();
  for (std::size_t i = 0; i < bytes.size(); ++i)
    if (p[i] != 0xFF) return false;
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

namespace {

/// What one config page holds.
struct CopyState {
  ConfigError error = ConfigError::kEmpty;  ///< kNone: valid
  std::uint32_t sequence = 0;
};

std::uint32_t commit_crc(const ConfigCommit& commit) {
  return crc32(std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(&commit),
                                             offsetof(ConfigCommit, crc32)));
}

/// Whether config page `copy` holds exactly `image` at offset 0.
bool page_holds(Port& port, int copy, const ConfigImage& image) {
  ConfigImage stored;
  auto stored_bytes =
      std::span<std::uint8_t>(reinterpret_cast<std::uint8_t*>(&stored), sizeof(stored));
  return port.read_config_page(copy, 0, stored_bytes) == PortStatus::kOk &&
         std::memcmp(&stored, &image, sizeof(image)) == 0;
}

/// Reads page `copy`; decodes it into `settings` (if not null) when valid.
CopyState read_copy(Port& port, int copy, const BoardConfig& board, ControllerSettings* settings) {
  CopyState state;
  ConfigImage image;
  ConfigCommit commit;
  auto image_bytes =
      std::span<std::uint8_t>(reinterpret_cast<std::uint8_t*>(&image), sizeof(image));
  auto commit_bytes =
      std::span<std::uint8_t>(reinterpret_cast<std::uint8_t*>(&commit), sizeof(commit));
  if (port.config_page_size() < sizeof(ConfigImage) + sizeof(ConfigCommit) ||
      port.read_config_page(copy, 0, image_bytes) != PortStatus::kOk ||
      port.read_config_page(copy, sizeof(ConfigImage), commit_bytes) != PortStatus::kOk) {
    state.error = ConfigError::kReadFailed;
    return state;
  }
  const auto decoded = decode_config(image_bytes, board);
  if (!decoded.ok()) {
    state.error = decoded.error();
    return state;
  }
  if (settings != nullptr) *settings = decoded.value();
  if (is_erased(commit_bytes)) {
    state.error = ConfigError::kNone;  // complete image, no commit: the oldest kind
    state.sequence = 0;
    return state;
  }
  if (commit.magic != kConfigCommitMagic || commit.crc32 != commit_crc(commit) ||
      commit.image_crc != image.crc32) {
    state.error = ConfigError::kCrcMismatch;  // a commit cut off mid-write
    return state;
  }
  state.error = ConfigError::kNone;
  state.sequence = commit.sequence;
  return state;
}

/// True if sequence `a` is newer than `b` (serial number arithmetic).
bool newer(std::uint32_t a, std::uint32_t b) {
  return static_cast<std::int32_t>(a - b) > 0;
}

/// The copy holding the newest valid configuration, or -1.
int newest_copy(const std::array<CopyState, kConfigCopies>& copies) {
  int best = -1;
  for (int c = 0; c < kConfigCopies; ++c) {
    const CopyState& s = copies[static_cast<std::size_t>(c)];
    if (s.error != ConfigError::kNone) continue;
    if (best < 0 || newer(s.sequence, copies[static_cast<std::size_t>(best)].sequence)) best = c;
  }
  return best;
}

}  // namespace

Result<std::uint32_t, protocol::Status> save_config(Port& port, const ControllerSettings& settings,
                                                    const BoardConfig& board) {
  using Saved = Result<std::uint32_t, protocol::Status>;
  if (port.config_page_size() < sizeof(ConfigImage) + sizeof(ConfigCommit))
    return Saved::failure(protocol::Status::kFlashError);
  std::array<CopyState, kConfigCopies> copies{};
  for (int c = 0; c < kConfigCopies; ++c)
    copies[static_cast<std::size_t>(c)] = read_copy(port, c, board, nullptr);
  const int newest = newest_copy(copies);
  // Rewrite the other page: the newest copy stays intact whatever happens.
  const int target = newest < 0 ? 0 : (newest + 1) % kConfigCopies;
  const std::uint32_t sequence =
      newest < 0 ? 1 : copies[static_cast<std::size_t>(newest)].sequence + 1;

  const ConfigImage image = encode_config(settings);
  // The newest copy already holds these settings: no erase (each sector is
  // rated for 10,000 erase cycles, and an erase masks interrupts for seconds).
  if (newest >= 0 && page_holds(port, newest, image)) return Saved::success(image.crc32);
  ConfigCommit commit{kConfigCommitMagic, sequence, image.crc32, 0};
  commit.crc32 = commit_crc(commit);
  const auto commit_bytes =
      std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(&commit), sizeof(commit));

  if (port.erase_config_page(target) != PortStatus::kOk)
    return Saved::failure(protocol::Status::kFlashError);
  if (port.write_config_page(target, 0, bytes_of(image)) != PortStatus::kOk)
    return Saved::failure(protocol::Status::kFlashError);
  ConfigImage readback;
  auto readback_bytes =
      std::span<std::uint8_t>(reinterpret_cast<std::uint8_t*>(&readback), sizeof(readback));
  if (port.read_config_page(target, 0, readback_bytes) != PortStatus::kOk ||
      std::memcmp(&readback, &image, sizeof(image)) != 0)
    return Saved::failure(protocol::Status::kFlashError);
  // Only a complete, verified image gets its commit.
  if (port.write_config_page(target, sizeof(ConfigImage), commit_bytes) != PortStatus::kOk)
    return Saved::failure(protocol::Status::kFlashError);
  ConfigCommit commit_readback;
  if (port.read_config_page(
          target, sizeof(ConfigImage),
          std::span<std::uint8_t>(reinterpret_cast<std::uint8_t*>(&commit_readback),
                                  sizeof(commit_readback))) != PortStatus::kOk ||
      std::memcmp(&commit_readback, &commit, sizeof(commit)) != 0)
    return Saved::failure(protocol::Status::kFlashError);
  return Saved::success(image.crc32);
}

Loaded load_config(Port& port, const BoardConfig& board) {
  std::array<CopyState, kConfigCopies> copies{};
  std::array<ControllerSettings, kConfigCopies> settings{};
  for (int c = 0; c < kConfigCopies; ++c) {
    const auto k = static_cast<std::size_t>(c);
    copies[k] = read_copy(port, c, board, &settings[k]);
  }
  const int newest = newest_copy(copies);
  if (newest >= 0) return Loaded::success(settings[static_cast<std::size_t>(newest)]);
  for (const CopyState& s : copies)
    if (s.error != ConfigError::kEmpty) return Loaded::failure(s.error);
  return Loaded::failure(ConfigError::kEmpty);
}

}  // namespace flutterscan::firmware
