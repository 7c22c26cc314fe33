#include "imaging/capture_descriptor.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace flutterscan::imaging {
namespace {

/// Thrown inside from_descriptor only, turned into its error.
struct FieldError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

const nlohmann::json& field(const nlohmann::json& object, const char* name) {
  if (!object.contains(name)) throw FieldError(std::string("missing field '") + name + "'");
  return object.at(name);
}

double number(const nlohmann::json& object, const char* name) {
  const auto& value = field(object, name);
  if (!value.is_number()) throw FieldError(std::string("field '") + name + "' must be a number");
  return value.get<double>();
}

/// A count or index (channels, LEDs, bits): an integer within +-1e6, so that the
/// conversion to int is defined whatever the file says (issue 20).
int small_integer(double value, const std::string& name) {
  if (!(std::abs(value) <= 1e6) || value != std::floor(value))
    throw FieldError("field '" + name + "' must be a whole number (within +-1000000)");
  return static_cast<int>(value);
}

int integer_field(const nlohmann::json& object, const char* name) {
  return small_integer(number(object, name), std::string(name));
}

/// `bit_depth`: a whole number of bits, 1 to 16.
int bit_depth_field(const nlohmann::json& object) {
  const int bits = integer_field(object, "bit_depth");
  if (bits < 1 || bits > 16) throw FieldError("field 'bit_depth' must be 1 to 16");
  return bits;
}

/// `bayer`: "RGGB" for a raw mosaic; absent or null for none.
bool bayer_field(const nlohmann::json& object) {
  if (!object.contains("bayer") || object.at("bayer").is_null()) return false;
  if (object.at("bayer") != "RGGB") throw FieldError("field 'bayer' must be \"RGGB\" or null");
  return true;
}

/// A list of strings (`name` for the message).
std::vector<std::string> strings(const nlohmann::json& value, const std::string& name) {
  if (!value.is_array()) throw FieldError("field '" + name + "' must be an array of strings");
  std::vector<std::string> out;
  for (const auto& item : value) {
    if (!item.is_string()) throw FieldError("field '" + name + "' must hold only strings");
    out.push_back(item.get<std::string>());
  }
  return out;
}

std::vector<double> numbers(const nlohmann::json& value, const std::string& name) {
  if (!value.is_array()) throw FieldError("field '" + name + "' must be an array of numbers");
  std::vector<double> out;
  for (const auto& item : value) {
    if (!item.is_number()) throw FieldError("field '" + name + "' must hold only numbers");
    out.push_back(item.get<double>());
  }
  return out;
}

const char* encoding_name(Encoding encoding) {
  switch (encoding) {
    case Encoding::kLinear:
      return "linear";
    case Encoding::kSrgb:
      return "srgb";
    case Encoding::kGamma:
      return "gamma";
  }
  return "linear";
}

}  // namespace

std::string direction_name(Direction direction) {
  switch (direction) {
    case Direction::kPlusX:
      return "+x";
    case Direction::kMinusX:
      return "-x";
    case Direction::kPlusY:
      return "+y";
    case Direction::kMinusY:
      return "-y";
  }
  return "+x";
}

std::string pixel_model_name(PixelModel model) {
  switch (model) {
    case PixelModel::kBandLimited:
      return "band-limited";
    case PixelModel::kTapGrid:
      return "tap-grid";
    case PixelModel::kBoxAperture:
      break;
  }
  return "box-aperture";
}

bool parse_pixel_model(const std::string& text, PixelModel& model) {
  for (PixelModel m : {PixelModel::kBoxAperture, PixelModel::kBandLimited, PixelModel::kTapGrid})
    if (pixel_model_name(m) == text) {
      model = m;
      return true;
    }
  return false;
}

bool parse_direction(const std::string& text, Direction& direction) {
  for (Direction d : {Direction::kPlusX, Direction::kMinusX, Direction::kPlusY, Direction::kMinusY})
    if (direction_name(d) == text) {
      direction = d;
      return true;
    }
  return false;
}

nlohmann::json to_descriptor(const CaptureModel& m) {
  std::string digits(static_cast<std::size_t>(m.code.length()), '0');
  m.code.format(digits);
  nlohmann::json crosstalk = nlohmann::json::array();
  for (int c = 0; c < m.channels; ++c) {
    nlohmann::json row = nlohmann::json::array();
    for (int k = 0; k < m.leds; ++k)
      row.push_back(m.crosstalk[static_cast<std::size_t>(c * m.leds + k)]);
    crosstalk.push_back(row);
  }
  nlohmann::json out = {
      {"format", kDescriptorFormat},
      {"version", kDescriptorVersion},
      {"code", digits},
      {"code_leds", m.code.leds()},
      {"led_of_bit", std::vector<int>(m.led_of_bit.begin(), m.led_of_bit.begin() + m.code.leds())},
      {"blur_px", m.blur_px},
      {"speed_ratio", m.speed_ratio},
      {"pixel_model", pixel_model_name(m.pixel_model)},
      {"direction", direction_name(m.direction)},
      {"channels", m.channels},
      {"leds", m.leds},
      {"crosstalk", crosstalk},
      {"led_electrons_per_slot", m.led_electrons},
      {"ambient_electrons", m.ambient_electrons},
      {"black_level_dn", m.black_level},
      {"gain_e_per_dn", m.gain},
      {"read_noise_e", m.read_noise},
      {"full_well_e", m.full_well},
      {"bit_depth", m.bit_depth},
      {"encoding", encoding_name(m.encoding)},
      {"gamma", m.gamma},
      {"bayer", m.bayer_rggb ? nlohmann::json("RGGB") : nlohmann::json(nullptr)},
  };
  if (!m.block_offsets_px.empty()) out["block_offsets_px"] = m.block_offsets_px;
  return out;
}

Result<CaptureModel, std::string> from_descriptor(const nlohmann::json& d) {
  using Out = Result<CaptureModel, std::string>;
  try {
    if (!d.is_object()) throw FieldError("a descriptor is a JSON object");
    const auto& format = field(d, "format");
    if (!format.is_string() || format.get<std::string>() != kDescriptorFormat)
      throw FieldError(std::string("field 'format' must be \"") + kDescriptorFormat + "\"");
    const double version = number(d, "version");
    if (version != kDescriptorVersion)
      throw FieldError("descriptor version " + nlohmann::json(version).dump() +
                       " is not supported (this flutterscan reads version " +
                       std::to_string(kDescriptorVersion) + ")");
    CaptureModel m;
    const auto& code_field = field(d, "code");
    if (!code_field.is_string()) throw FieldError("field 'code' must be a string of digits");
    const int code_leds = integer_field(d, "code_leds");
    const auto code = LedCode::parse(code_field.get<std::string>(), code_leds);
    if (!code.ok()) {
      char message[160];
      describe(code.error(), message);
      throw FieldError(std::string("field 'code': ") + message);
    }
    m.code = code.value();
    const auto led_of_bit = numbers(field(d, "led_of_bit"), "led_of_bit");
    if (static_cast<int>(led_of_bit.size()) != code_leds)
      throw FieldError("field 'led_of_bit' needs one entry per code bit (" +
                       std::to_string(code_leds) + ")");
    for (std::size_t k = 0; k < led_of_bit.size(); ++k)
      m.led_of_bit[k] = small_integer(led_of_bit[k], std::string("led_of_bit"));
    m.blur_px = number(d, "blur_px");
    if (d.contains("speed_ratio")) m.speed_ratio = number(d, "speed_ratio");
    if (d.contains("block_offsets_px"))
      m.block_offsets_px = numbers(d.at("block_offsets_px"), "block_offsets_px");
    if (d.contains("pixel_model")) {
      const auto& pixel = d.at("pixel_model");
      if (!pixel.is_string() || !parse_pixel_model(pixel.get<std::string>(), m.pixel_model))
        throw FieldError(
            "field 'pixel_model' must be \"box-aperture\", \"band-limited\" or \"tap-grid\"");
    }
    const auto& direction = field(d, "direction");
    if (!direction.is_string() || !parse_direction(direction.get<std::string>(), m.direction))
      throw FieldError("field 'direction' must be \"+x\", \"-x\", \"+y\" or \"-y\"");
    m.channels = integer_field(d, "channels");
    m.leds = integer_field(d, "leds");
    const auto& crosstalk = field(d, "crosstalk");
    if (!crosstalk.is_array()) throw FieldError("field 'crosstalk' must be an array of rows");
    m.crosstalk.clear();
    for (std::size_t r = 0; r < crosstalk.size(); ++r) {
      const auto row = numbers(crosstalk[r], "crosstalk[" + std::to_string(r) + "]");
      if (static_cast<int>(row.size()) != m.leds)
        throw FieldError("field 'crosstalk' row " + std::to_string(r) + " needs " +
                         std::to_string(m.leds) + " entries");
      m.crosstalk.insert(m.crosstalk.end(), row.begin(), row.end());
    }
    m.led_electrons = numbers(field(d, "led_electrons_per_slot"), "led_electrons_per_slot");
    if (static_cast<int>(m.led_electrons.size()) != m.leds)
      throw FieldError("field 'led_electrons_per_slot' needs one entry per LED (" +
                       std::to_string(m.leds) + ")");
    m.ambient_electrons = numbers(field(d, "ambient_electrons"), "ambient_electrons");
    if (static_cast<int>(m.ambient_electrons.size()) != m.channels)
      throw FieldError("field 'ambient_electrons' needs one entry per channel (" +
                       std::to_string(m.channels) + ")");
    m.black_level = number(d, "black_level_dn");
    m.gain = number(d, "gain_e_per_dn");
    m.read_noise = number(d, "read_noise_e");
    m.full_well = number(d, "full_well_e");
    m.bit_depth = bit_depth_field(d);
    const auto& encoding = field(d, "encoding");
    const std::string encoding_text = encoding.is_string() ? encoding.get<std::string>() : "";
    if (encoding_text == "linear")
      m.encoding = Encoding::kLinear;
    else if (encoding_text == "srgb")
      m.encoding = Encoding::kSrgb;
    else if (encoding_text == "gamma")
      m.encoding = Encoding::kGamma;
    else
      throw FieldError("field 'encoding' must be \"linear\", \"srgb\" or \"gamma\"");
    if (d.contains("gamma")) m.gamma = number(d, "gamma");
    m.bayer_rggb = bayer_field(d);
    if (auto problem = capture_model_problem(m); !problem.empty()) throw FieldError(problem);
    return Out::success(m);
  } catch (const FieldError& e) {
    return Out::failure(e.what());
  }
}

Result<RecordedFrame, std::string> recorded_frame_from_descriptor(const nlohmann::json& d) {
  using Out = Result<RecordedFrame, std::string>;
  try {
    if (!d.is_object()) throw FieldError("a descriptor is a JSON object");
    RecordedFrame r;
    if (d.contains("bit_depth")) r.bit_depth = bit_depth_field(d);
    r.bayer_rggb = bayer_field(d);
    if (!d.contains("capture")) return Out::success(r);
    const auto& capture = d.at("capture");
    if (!capture.is_object()) throw FieldError("field 'capture' must be an object");
    if (capture.contains("sequence")) {
      const auto& sequence = capture.at("sequence");
      // nlohmann reads a non-negative integer as unsigned; a built one may be signed.
      if (!sequence.is_number_integer() ||
          (!sequence.is_number_unsigned() && sequence.get<std::int64_t>() < 0))
        throw FieldError("field 'capture.sequence' must be a whole number >= 0");
      r.sequence = sequence.get<std::uint64_t>();
    }
    if (capture.contains("timestamp_ns")) {
      const auto& timestamp = capture.at("timestamp_ns");
      if (!timestamp.is_number_integer() ||
          (timestamp.is_number_unsigned() &&
           timestamp.get<std::uint64_t>() > std::numeric_limits<std::int64_t>::max()))
        throw FieldError(
            "field 'capture.timestamp_ns' must be a whole number of nanoseconds "
            "(64-bit signed)");
      r.timestamp_ns = timestamp.get<std::int64_t>();
    }
    if (capture.contains("truth")) r.truth = strings(capture.at("truth"), "capture.truth");
    if (capture.contains("truth_in_view"))
      r.truth_in_view = strings(capture.at("truth_in_view"), "capture.truth_in_view");
    return Out::success(r);
  } catch (const FieldError& e) {
    return Out::failure(e.what());
  }
}

}  // namespace flutterscan::imaging
