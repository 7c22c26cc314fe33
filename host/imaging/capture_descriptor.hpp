#pragma once
// The capture descriptor: a CaptureModel as JSON, the file that travels beside
// every captured or simulated frame (docs/formats.md), and the one reader of it:
// the capture model (`flutterscan deblur --descriptor`, replay) and what the
// files camera takes of a recorded frame share its field checks.

#include <nlohmann/json.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "flutterscan/common/result.hpp"
#include "imaging/capture_model.hpp"

namespace flutterscan::imaging {

inline constexpr const char* kDescriptorFormat = "flutterscan-capture";
inline constexpr int kDescriptorVersion = 1;

/// \brief The descriptor of `model`.
nlohmann::json to_descriptor(const CaptureModel& model);

/// \brief Reads a descriptor; the error names the field and what is wrong with it.
Result<CaptureModel, std::string> from_descriptor(const nlohmann::json& descriptor);

/// \brief What a descriptor says of the recorded frame beside it, every field
/// optional: what the files camera replays (a session writes the `capture` object).
struct RecordedFrame {
  std::optional<int> bit_depth;              ///< `bit_depth`, 1 to 16
  bool bayer_rggb = false;                   ///< `bayer`: "RGGB" (else absent or null)
  std::optional<std::uint64_t> sequence;     ///< `capture.sequence`, the camera's
  std::optional<std::int64_t> timestamp_ns;  ///< `capture.timestamp_ns`
  std::vector<std::string> truth;            ///< `capture.truth`: the labels' values
  std::vector<std::string> truth_in_view;    ///< `capture.truth_in_view`
};

/// \brief Reads a descriptor's RecordedFrame fields with from_descriptor's
/// checks; the other fields are not read. The error names the field.
Result<RecordedFrame, std::string> recorded_frame_from_descriptor(const nlohmann::json& descriptor);

/// \brief "+x", "-x", "+y", "-y".
std::string direction_name(Direction direction);
/// \brief Parses a direction name; false if it is none of the four.
bool parse_direction(const std::string& text, Direction& direction);

/// \brief "box-aperture", "band-limited" or "tap-grid" (the descriptor's pixel_model).
std::string pixel_model_name(PixelModel model);
/// \brief Reads pixel_model_name()'s text; false (and `model` untouched) for anything else.
bool parse_pixel_model(const std::string& text, PixelModel& model);

}  // namespace flutterscan::imaging
