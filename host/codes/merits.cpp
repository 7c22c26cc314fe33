#include "codes/merits.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "codes/spectrum.hpp"

namespace flutterscan::codes {
namespace {

struct MeritInfo {
  Merit merit;
  std::string_view name;
  std::string_view unit;
};

constexpr std::array<MeritInfo, 6> kMeritInfo = {{
    {Merit::kMaxMin, "maxmin", "dB"},
    {Merit::kAvgMin, "avgmin", "dB"},
    {Merit::kPairs, "pairs", "dB"},
    {Merit::kSingle, "single", "|DFT| (code sum 1)"},
    {Merit::kJoint, "joint", "e-"},
    {Merit::kMse, "mse", "1/e-"},
}};

/// Per-LED minimum over the grid of the seed's dB.
std::array<double, kMaxLeds> per_led_min_db(const GridSpectra& spectra) {
  std::array<double, kMaxLeds> minima{};
  for (int k = 0; k < spectra.leds; ++k) {
    double lowest = std::numeric_limits<double>::infinity();
    for (const auto& value : spectra.led(k)) lowest = std::min(lowest, std::norm(value));
    minima[static_cast<std::size_t>(k)] = seed_db(std::sqrt(lowest), spectra.length);
  }
  return minima;
}

/// Calls visit(j, J) for every grid frequency j.
template <typename Visit>
void for_each_joint_sample(const GridSpectra& spectra, const LightModel& light, Visit visit) {
  const auto leds = static_cast<std::size_t>(spectra.leds);
  const JointWeights weights({spectra.on_slots.data(), leds}, spectra.length, light);
  std::array<std::complex<double>, kMaxLeds> at{};
  for (std::size_t j = 0; j < spectra.frequency.size(); ++j) {
    for (std::size_t k = 0; k < leds; ++k) at[k] = spectra.led(static_cast<int>(k))[j];
    visit(j, weights.value({at.data(), leds}));
  }
}

std::vector<double> joint_samples(const GridSpectra& spectra, const LightModel& light) {
  std::vector<double> samples(spectra.frequency.size());
  for_each_joint_sample(spectra, light, [&](std::size_t j, double value) { samples[j] = value; });
  return samples;
}

}  // namespace

std::string_view merit_name(Merit merit) {
  for (const auto& info : kMeritInfo)
    if (info.merit == merit) return info.name;
  return "?";
}

std::optional<Merit> merit_from_name(std::string_view name) {
  for (const auto& info : kMeritInfo)
    if (info.name == name) return info.merit;
  return std::nullopt;
}

std::string_view merit_unit(Merit merit) {
  for (const auto& info : kMeritInfo)
    if (info.merit == merit) return info.unit;
  return "";
}

std::string merit_inapplicable(Merit merit, const LedCode& code, const MeritSettings& settings) {
  switch (merit) {
    case Merit::kPairs:
      if (code.leds() < 3) return "pairs needs a code of at least 3 LEDs";
      break;
    case Merit::kSingle:
      if (code.leds() != 1) return "single is the merit of one-LED codes";
      if (settings.single_pad < code.length())
        return "single: the padded length " + std::to_string(settings.single_pad) +
               " is shorter than the code (" + std::to_string(code.length()) + " slots)";
      break;
    case Merit::kJoint:
    case Merit::kMse: {
      const auto& light = settings.light;
      if (!(light.electrons > 0) || !(light.cap > 0) || !(light.read_noise >= 0))
        return std::string(merit_name(merit)) + " needs electrons > 0, cap > 0 and read noise >= 0";
      if (light.crosstalk && light.crosstalk->leds != code.leds())
        return "the crosstalk matrix has " + std::to_string(light.crosstalk->leds) +
               " columns (LEDs) but the code has " + std::to_string(code.leds()) + " LEDs";
      if (light.crosstalk &&
          (light.crosstalk->channels < 1 || light.crosstalk->channels > kMaxLeds))
        return "the crosstalk matrix needs 1 to 4 rows (camera channels)";
      break;
    }
    default:
      break;
  }
  return {};
}

std::vector<double> merit_grid(Merit merit, int length, const MeritSettings& settings,
                               int dense_points) {
  int points = 0;
  double step = 0;
  switch (merit) {
    case Merit::kMaxMin:
    case Merit::kAvgMin:
    case Merit::kPairs: {
      const int size = seed_grid_size(length);
      points = size / 2 + 1;
      step = 1.0 / size;
      break;
    }
    case Merit::kSingle:
      points = settings.single_pad / 2 + 1;
      step = 1.0 / settings.single_pad;
      break;
    case Merit::kJoint:
    case Merit::kMse:
      points = dense_points;
      step = 0.5 / (dense_points - 1);
      break;
  }
  std::vector<double> grid(static_cast<std::size_t>(points));
  for (int j = 0; j < points; ++j) grid[static_cast<std::size_t>(j)] = step * j;
  return grid;
}

GridSpectra grid_spectra(Merit merit, const LedCode& code, const MeritSettings& settings,
                         int dense_points) {
  GridSpectra spectra;
  spectra.leds = code.leds();
  spectra.length = code.length();
  spectra.frequency = merit_grid(merit, code.length(), settings, dense_points);
  const std::size_t points = spectra.frequency.size();
  // Every grid is bins 0..size/2 of a size-point DFT.
  const int size = static_cast<int>(2 * (points - 1));
  spectra.h.reserve(points * static_cast<std::size_t>(code.leds()));
  for (int k = 0; k < code.leds(); ++k) {
    const auto sequence = led_sequence(code, k);
    const auto bins = padded_dft(sequence, size);
    spectra.h.insert(spectra.h.end(), bins.begin(), bins.end());
    spectra.on_slots[static_cast<std::size_t>(k)] = code.on_slots(k);
  }
  return spectra;
}

double merit_on_grid(Merit merit, const GridSpectra& spectra, const MeritSettings& settings) {
  switch (merit) {
    case Merit::kMaxMin: {
      const auto minima = per_led_min_db(spectra);
      return *std::max_element(minima.begin(), minima.begin() + spectra.leds);
    }
    case Merit::kAvgMin: {
      const auto minima = per_led_min_db(spectra);
      double sum = 0;
      for (int k = 0; k < spectra.leds; ++k) sum += minima[static_cast<std::size_t>(k)];
      return sum / spectra.leds;
    }
    case Merit::kPairs: {
      const auto m = per_led_min_db(spectra);
      return (std::max(m[0], m[1]) + std::max(m[0], m[2])) / 2.0;
    }
    case Merit::kSingle: {
      const int ones = spectra.on_slots[0];
      if (ones == 0) return 0.0;
      double lowest = std::numeric_limits<double>::infinity();
      for (const auto& value : spectra.led(0)) lowest = std::min(lowest, std::norm(value));
      return std::sqrt(lowest) / ones;
    }
    case Merit::kJoint: {
      double lowest = std::numeric_limits<double>::infinity();
      for_each_joint_sample(spectra, settings.light,
                            [&](std::size_t, double value) { lowest = std::min(lowest, value); });
      return lowest;
    }
    case Merit::kMse: {
      double sum = 0;
      for_each_joint_sample(spectra, settings.light, [&](std::size_t, double value) {
        sum += 1.0 / (value + settings.mse_eps);
      });
      return sum / static_cast<double>(spectra.frequency.size());
    }
  }
  return 0.0;
}

JointWeights::JointWeights(std::span<const int> on_slots, int length, const LightModel& light)
    : leds_(static_cast<int>(on_slots.size())),
      channels_(light.crosstalk ? light.crosstalk->channels : leds_),
      diagonal_(!light.crosstalk) {
  const double peak = light.cap * light.electrons / length;
  for (int k = 0; k < leds_; ++k) {
    const int n = on_slots[static_cast<std::size_t>(k)];
    intensity_[static_cast<std::size_t>(k)] = n > 0 ? std::min(light.electrons / n, peak) : 0.0;
  }
  const double read_variance = light.read_noise * light.read_noise;
  for (int c = 0; c < channels_; ++c) {
    double variance = read_variance;
    for (int k = 0; k < leds_; ++k) {
      const double m = light.crosstalk
                           ? light.crosstalk->gain[static_cast<std::size_t>(c * leds_ + k)]
                           : (c == k ? 1.0 : 0.0);
      variance +=
          m * intensity_[static_cast<std::size_t>(k)] * on_slots[static_cast<std::size_t>(k)];
    }
    for (int k = 0; k < leds_; ++k) {
      const double m = light.crosstalk
                           ? light.crosstalk->gain[static_cast<std::size_t>(c * leds_ + k)]
                           : (c == k ? 1.0 : 0.0);
      amplitude_[static_cast<std::size_t>(c * leds_ + k)] =
          variance > 0 ? m * intensity_[static_cast<std::size_t>(k)] / std::sqrt(variance) : 0.0;
    }
  }
}

double JointWeights::value(std::span<const std::complex<double>> h_at_frequency) const {
  double total = 0;
  if (diagonal_) {
    for (int k = 0; k < leds_; ++k) {
      const double a = amplitude_[static_cast<std::size_t>(k * leds_ + k)];
      total += a * a * std::norm(h_at_frequency[static_cast<std::size_t>(k)]);
    }
    return total;
  }
  for (int c = 0; c < channels_; ++c) {
    std::complex<double> channel = 0;
    for (int k = 0; k < leds_; ++k)
      channel += amplitude_[static_cast<std::size_t>(c * leds_ + k)] *
                 h_at_frequency[static_cast<std::size_t>(k)];
    total += std::norm(channel);
  }
  return total;
}

double merit_objective(Merit merit, double value) {
  constexpr double kFloor = 1e-30;
  switch (merit) {
    case Merit::kSingle:
      return 20.0 * std::log10(std::max(value, kFloor));
    case Merit::kJoint:
      return 10.0 * std::log10(std::max(value, kFloor));
    case Merit::kMse:
      return -10.0 * std::log10(std::max(value, kFloor));
    default:
      return value;
  }
}

double merit_from_objective(Merit merit, double objective) {
  switch (merit) {
    case Merit::kSingle:
      return std::pow(10.0, objective / 20.0);
    case Merit::kJoint:
      return std::pow(10.0, objective / 10.0);
    case Merit::kMse:
      return std::pow(10.0, -objective / 10.0);
    default:
      return objective;
  }
}

double joint_information(const LedCode& code, const LightModel& light, double f) {
  std::array<int, kMaxLeds> on_slots{};
  std::array<std::complex<double>, kMaxLeds> h{};
  for (int k = 0; k < code.leds(); ++k) {
    on_slots[static_cast<std::size_t>(k)] = code.on_slots(k);
    h[static_cast<std::size_t>(k)] = dtft(led_sequence(code, k), f);
  }
  const auto leds = static_cast<std::size_t>(code.leds());
  return JointWeights({on_slots.data(), leds}, code.length(), light).value({h.data(), leds});
}

Result<double, std::string> evaluate_merit(Merit merit, const LedCode& code,
                                           const MeritSettings& settings) {
  if (auto why = merit_inapplicable(merit, code, settings); !why.empty())
    return Result<double, std::string>::failure(why);
  const GridSpectra spectra = grid_spectra(merit, code, settings, settings.dense_points);
  if (merit != Merit::kJoint)
    return Result<double, std::string>::success(merit_on_grid(merit, spectra, settings));
  const auto samples = joint_samples(spectra, settings.light);
  const Minimum minimum = minimise_over_frequency(
      samples, [&](double f) { return joint_information(code, settings.light, f); });
  return Result<double, std::string>::success(minimum.refined_value);
}

}  // namespace flutterscan::codes
