#pragma once
// The capture descriptor: a CaptureModel as JSON, the file that travels beside
// every captured or simulated frame (docs/formats.md).

#include <nlohmann/json.hpp>

#include <string>

#include "flutterscan/common/result.hpp"
#include "imaging/capture_model.hpp"

namespace flutterscan::imaging {

inline constexpr const char* kDescriptorFormat = "flutterscan-capture";
inline constexpr int kDescriptorVersion = 1;

/// \brief The descriptor of `model`.
nlohmann::json to_descriptor(const CaptureModel& model);

/// \brief Reads a descriptor; the error names the field and what is wrong with it.
Result<CaptureModel, std::string> from_descriptor(const nlohmann::json& descriptor);

/// \brief "+x", "-x", "+y", "-y".
std::string direction_name(Direction direction);
/// \brief Parses a direction name; false if it is none of the four.
bool parse_direction(const std::string& text, Direction& direction);

/// \brief "box-aperture", "band-limited" or "tap-grid" (the descriptor's pixel_model).
std::string pixel_model_name(PixelModel model);
/// \brief Reads pixel_model_name()'s text; false (and `model` untouched) for anything else.
bool parse_pixel_model(const std::string& text, PixelModel& model);

}  // namespace flutterscan::imaging
