#pragma once
// The capture model of one frame (docs/conventions.md, "The forward model"): which code lit it,
// how far the scene moved, how LED light reaches the camera channels, and the
// camera's EMVA 1288 noise parameters. From it come each channel's effective
// motion PSF and noise variance; the simulator and every deblurring method use
// the same functions, so they agree to the last tap.

#include <array>
#include <string>
#include <vector>

#include "flutterscan/common/led_code.hpp"
#include "imaging/image.hpp"
#include "imaging/motion_psf.hpp"

namespace flutterscan::imaging {

/// \brief Scene motion during the exposure: +x = toward larger column index.
enum class Direction { kPlusX, kMinusX, kPlusY, kMinusY };

/// \brief True when the scene moves along image rows (+x or -x).
inline bool moves_along_x(Direction direction) {
  return direction == Direction::kPlusX || direction == Direction::kMinusX;
}

/// \brief How stored pixel values relate to light.
enum class Encoding { kLinear, kSrgb, kGamma };

/// \brief Slowest end / start speed ratio a capture model takes (and 1 / it the
/// fastest): a belt that stops or reverses within an exposure is outside the model.
inline constexpr double kMinSpeedRatio = 0.2;

struct CaptureModel {
  LedCode code;                                      ///< the exposure's LED pattern
  std::array<int, kMaxLeds> led_of_bit{0, 1, 2, 3};  ///< code bit k drives LED led_of_bit[k]
  double blur_px = 52;                               ///< total motion during the exposure, pixels
  /// Speed at the end of the exposure / speed at its start (constant acceleration
  /// between them, same total motion); 1 = constant speed.
  double speed_ratio = 1;
  /// A speed that wanders within the exposure on top of that (belt jitter):
  /// extra displacement (px) at the ends of equal-time blocks but the last
  /// (add_block_offsets(), motion_psf.hpp); empty = none.
  std::vector<double> block_offsets_px;
  PixelModel pixel_model = PixelModel::kBoxAperture;  ///< how motion meets the pixel grid
  Direction direction = Direction::kPlusX;
  int channels = 3;  ///< camera channels: 3 (RGB) or 1 (mono)
  /// crosstalk[c * leds + led]: share of LED `led`'s light in channel c (rows = channels).
  std::vector<double> crosstalk = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  int leds = 3;                                   ///< physical LEDs (columns of crosstalk)
  std::vector<double> led_electrons = {0, 0, 0};  ///< I_k: e- per slot, white object, own channel
  std::vector<double> ambient_electrons = {0, 0, 0};  ///< e- per exposure per channel, white
  double black_level = 0;                             ///< DN
  double gain = 1;                                    ///< conversion gain, e- per DN
  double read_noise = 4;                              ///< e- rms
  double full_well = 12000;                           ///< e-
  int bit_depth = 12;
  Encoding encoding = Encoding::kLinear;
  double gamma = 2.2;       ///< for Encoding::kGamma
  bool bayer_rggb = false;  ///< raw Bayer RGGB mosaic rather than RGB
};

/// \brief The first problem with `model` (empty if none): non-finite or negative
/// parameters, sizes that disagree, a code with more bits than LEDs.
std::string capture_model_problem(const CaptureModel& model);

/// \brief Electrons per slot of each code bit under the light budget of
/// docs/conventions.md: I = min(E / n, cap * E / L), n the bit's on-slots.
std::vector<double> budgeted_led_electrons(const LedCode& code, double electrons, double cap);

/// \brief Object displacement (pixels) at the L + 1 slot edges: blur_px in all,
/// quadratic in the slot index when speed_ratio != 1, plus the block offsets
/// (motion_psf.hpp).
std::vector<double> slot_edges(const CaptureModel& model);

/// \brief Channel c's motion PSF along the motion, in e- per unit reflectance:
/// tap j is the light that a white point deposits j pixels downstream. Slot t
/// spans [slot_edges[t], slot_edges[t + 1]] of motion (sub-pixel exact), laid
/// onto the pixels by the model's pixel model; ambient light is spread over
/// every slot alike. Sums to the white level of the channel.
std::vector<double> channel_psf(const CaptureModel& model, int channel);

/// \brief True if every channel's PSF is a multiple of every other's (one code
/// on every channel): such a frame carries no motion information across channels.
bool channels_share_one_code(const CaptureModel& model);

/// \brief Expected electrons a white object gives channel c over the exposure.
double channel_white_electrons(const CaptureModel& model, int channel);

/// \brief Noise variance (e-^2) of channel c at a mean signal of `signal_electrons`:
/// shot noise, read noise and quantisation.
double channel_noise_variance(const CaptureModel& model, double signal_electrons);

/// \brief Rows apart that noise_level_mean() reads.
inline constexpr int kNoiseLevelRowStep = 4;

/// \brief A channel plane's mean electrons, the signal its noise level is taken at
/// (channel_noise_variance): over every 4th row, which gives it to well under 1%
/// on any frame at a quarter of the cost (RowLevels::mean_of_rows makes the same
/// value from a motion frame's row levels, reading no row).
double noise_level_mean(const Plane& plane);

}  // namespace flutterscan::imaging
