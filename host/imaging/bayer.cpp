#include "imaging/bayer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "imaging/image_checks.hpp"
#include "imaging/motion_frame.hpp"

namespace flutterscan::imaging {
namespace {

/// The four mosaic colours in plane order: site parity in x and y, camera channel.
struct BayerColour {
  int x_parity;
  int y_parity;
  int channel;
};
constexpr std::array<BayerColour, 4> kColours{{{0, 0, 0}, {1, 0, 1}, {0, 1, 1}, {1, 1, 2}}};

/// The camera channel sampled at mosaic site (x, y).
int channel_at(int x, int y) {
  return kColours[static_cast<std::size_t>((y % 2) * 2 + (x % 2))].channel;
}

/// A full-resolution PSF delayed by `delay` pixels and summed over pixel pairs:
/// tap k of the result is the light over delayed full-resolution pixels 2k and 2k+1.
std::vector<double> pair_summed_psf(const std::vector<double>& full, int delay) {
  std::vector<double> half((full.size() + static_cast<std::size_t>(delay) + 2) / 2 + 1, 0.0);
  for (std::size_t j = 0; j < full.size(); ++j) {
    const std::size_t at = j + static_cast<std::size_t>(delay);
    half[at / 2] += full[j];
  }
  while (half.size() > 1 && half.back() == 0.0) half.pop_back();
  return half;
}

/// Colour `colour` of `mosaic` (original orientation) at half resolution along
/// the motion and full resolution across it: rows (columns for y motion) of the
/// other parity take the mean of their two neighbours of this colour.
/// `along` is the even length along the motion that is used.
Plane row_aligned_plane(const Plane& mosaic, const BayerColour& colour, bool along_x, int along) {
  const int width = along_x ? along / 2 : mosaic.width;
  const int height = along_x ? mosaic.height : along / 2;
  Plane out(width, height);
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) {
      // (x, y): this plane sample's mosaic position; `across` is its coordinate across the motion.
      const int x = along_x ? 2 * i + colour.x_parity : i;
      const int y = along_x ? j : 2 * j + colour.y_parity;
      const int across = along_x ? y : x;
      const int parity = along_x ? colour.y_parity : colour.x_parity;
      const int limit = along_x ? mosaic.height : mosaic.width;
      if ((across & 1) == parity) {
        out.at(i, j) = mosaic.at(x, y);
        continue;
      }
      double sum = 0;
      int count = 0;
      for (int step : {-1, 1}) {
        const int neighbour = across + step;
        if (neighbour < 0 || neighbour >= limit) continue;
        sum += along_x ? mosaic.at(x, neighbour) : mosaic.at(neighbour, y);
        ++count;
      }
      out.at(i, j) = static_cast<float>(sum / count);
    }
  return out;
}

/// Upsamples a motion-frame latent of pair samples (sample m centred on column
/// 2m + 0.5) to `width` full-resolution columns by linear interpolation.
Plane upsample_pairs(const Plane& half, int width) {
  constexpr double kCentre = 0.5;
  Plane out(width, half.height);
  const int last = half.width - 1;
  for (int x = 0; x < width; ++x) {
    const double u = std::clamp((x - kCentre) / 2.0, 0.0, static_cast<double>(last));
    const int i0 = static_cast<int>(std::floor(u));
    const int i1 = std::min(i0 + 1, last);
    const auto t = static_cast<float>(u - i0);
    for (int y = 0; y < half.height; ++y)
      out.at(x, y) = (1 - t) * half.at(i0, y) + t * half.at(i1, y);
  }
  return out;
}

/// `motion` (motion-frame samples of the even part along the motion) grown to
/// the frame's `length` samples along the motion: an odd frame's last camera
/// column (row) along the motion repeats its neighbour. In the motion frame
/// that camera pixel is the last sample, or the first when the motion runs
/// toward smaller camera index.
Plane pad_along_motion(const Plane& motion, Direction direction, int length) {
  if (motion.width == length) return motion;
  const bool extra_first =
      position_along_motion(direction, length - 1, length - 1, length, length) == 0;
  const int shift = extra_first ? length - motion.width : 0;
  Plane out(length, motion.height);
  for (int y = 0; y < motion.height; ++y)
    for (int n = 0; n < length; ++n)
      out.at(n, y) = motion.at(std::clamp(n - shift, 0, motion.width - 1), y);
  return out;
}

Result<BayerDeblurResult, std::string> deblur_raw_planes(const Plane& mosaic,
                                                         const CaptureModel& model,
                                                         const DeblurOptions& options) {
  using Out = Result<BayerDeblurResult, std::string>;
  const bool along_x = moves_along_x(model.direction);
  const int length = length_along_motion(model.direction, mosaic.width, mosaic.height);
  const int along = length & ~1;  // even part along the motion
  if (model.blur_px / 2 >= along / 2.0)
    return Out::failure("the blur (" + std::to_string(model.blur_px) +
                        " px) is not shorter than the image along the motion (" +
                        std::to_string(along) + " px)");

  BayerDeblurResult result;
  std::vector<Plane> rows;
  std::vector<ChannelPsf> psfs;
  double white = 0;
  for (const BayerColour& colour : kColours) {
    rows.push_back(
        to_motion_frame(row_aligned_plane(mosaic, colour, along_x, along), model.direction));
    // Motion-frame column of this colour within each pair: where its first site
    // lands along the motion (of the even part, so reversing swaps the parity).
    const int offset = static_cast<int>(position_along_motion(model.direction, colour.x_parity,
                                                              colour.y_parity, along, along)) &
                       1;
    const double variance = channel_noise_variance(model, noise_level_mean(rows.back()));
    result.noise_variance.push_back(variance);
    psfs.push_back({pair_summed_psf(channel_psf(model, colour.channel), 1 - offset), variance});
    for (double tap : psfs.back().taps) white += tap;
  }
  if (white <= 0) return Out::failure("the capture model lights no channel: every PSF is zero");

  // Half as many samples along the motion carry the same edges: twice the gradient variance.
  const Plane latent = deconvolve_motion_rows(psfs, rows, 1.0 / (2.0 * options.gradient_variance),
                                              model.read_noise * model.read_noise, options);
  // Padded in the motion frame, turned back once.
  result.motion_latent = pad_along_motion(upsample_pairs(latent, along), model.direction, length);
  result.latent = from_motion_frame(result.motion_latent, model.direction);
  return Out::success(std::move(result));
}

}  // namespace

std::string bayer_mode_name(BayerMode mode) {
  switch (mode) {
    case BayerMode::kRawPlanes:
      return "raw";
    case BayerMode::kDemosaicFirst:
      return "demosaic";
  }
  return "?";
}

std::optional<BayerMode> bayer_mode_from_name(const std::string& name) {
  for (BayerMode m : {BayerMode::kRawPlanes, BayerMode::kDemosaicFirst})
    if (bayer_mode_name(m) == name) return m;
  return std::nullopt;
}

Image split_bayer_planes(const Plane& mosaic) {
  Image out;
  const int width = mosaic.width / 2, height = mosaic.height / 2;
  for (const BayerColour& colour : kColours) {
    Plane plane(width, height);
    for (int j = 0; j < height; ++j)
      for (int i = 0; i < width; ++i)
        plane.at(i, j) = mosaic.at(2 * i + colour.x_parity, 2 * j + colour.y_parity);
    out.channels.push_back(std::move(plane));
  }
  return out;
}

Image demosaic_bilinear(const Plane& mosaic) {
  Image out;
  for (int c = 0; c < 3; ++c) out.channels.emplace_back(mosaic.width, mosaic.height);
  for (int y = 0; y < mosaic.height; ++y)
    for (int x = 0; x < mosaic.width; ++x) {
      const int own = channel_at(x, y);
      out.channels[static_cast<std::size_t>(own)].at(x, y) = mosaic.at(x, y);
      // The other two channels: mean of the nearest sites of that channel. In
      // RGGB these are all at the same distance (2 edge, 2 or 4 diagonal, or 4
      // edge neighbours), so the plain mean is the bilinear interpolation.
      std::array<double, 3> sum{};
      std::array<int, 3> count{};
      std::array<int, 3> nearest{3, 3, 3};  // squared distance of the nearest site seen
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= mosaic.width || ny >= mosaic.height)
            continue;
          const auto c = static_cast<std::size_t>(channel_at(nx, ny));
          const int distance = dx * dx + dy * dy;
          if (distance < nearest[c]) {
            nearest[c] = distance;
            sum[c] = 0;
            count[c] = 0;
          }
          if (distance == nearest[c]) {
            sum[c] += mosaic.at(nx, ny);
            ++count[c];
          }
        }
      for (int c = 0; c < 3; ++c) {
        const auto k = static_cast<std::size_t>(c);
        if (c != own && count[k] > 0)
          out.channels[k].at(x, y) = static_cast<float>(sum[k] / count[k]);
      }
    }
  return out;
}

Result<BayerDeblurResult, std::string> deblur_bayer(const Plane& mosaic_electrons,
                                                    const CaptureModel& model,
                                                    const DeblurOptions& options, BayerMode mode) {
  using Out = Result<BayerDeblurResult, std::string>;
  if (auto problem = capture_model_problem(model); !problem.empty()) return Out::failure(problem);
  if (model.channels != 3)
    return Out::failure("a Bayer mosaic needs a 3-channel (RGB) capture model");
  if (mosaic_electrons.width < 2 || mosaic_electrons.height < 2)
    return Out::failure("a Bayer mosaic must be at least 2x2 pixels");
  // Before anything is sized by the blur or scaled by the light (image_checks.hpp).
  if (mosaic_electrons.pixels.size() !=
      static_cast<std::size_t>(mosaic_electrons.width) * mosaic_electrons.height)
    return Out::failure("the mosaic holds " + std::to_string(mosaic_electrons.pixels.size()) +
                        " pixels, not width x height");
  if (auto problem = model_scale_problem(model); !problem.empty()) return Out::failure(problem);
  if (auto problem = image_problem(Image{{mosaic_electrons}}); !problem.empty())
    return Out::failure(problem);
  if (auto problem = blur_fit_problem(
          model.blur_px,
          length_along_motion(model.direction, mosaic_electrons.width, mosaic_electrons.height), 1,
          "the blur");
      !problem.empty())
    return Out::failure(problem);
  if (mode == BayerMode::kDemosaicFirst) {
    auto frame = MotionFrame::make(demosaic_bilinear(mosaic_electrons), model.direction);
    if (!frame.ok()) return Out::failure(frame.error());
    auto r = deblur(frame.value(), model, options);
    if (!r.ok()) return Out::failure(r.error());
    BayerDeblurResult result;
    result.noise_variance = std::move(r.value().noise_variance);
    result.motion_latent = std::move(r.value().latent);
    result.latent = frame.value().to_camera(result.motion_latent);
    return Out::success(std::move(result));
  }
  if (!(options.gradient_variance > 0) || !std::isfinite(options.gradient_variance))
    return Out::failure("the prior gradient variance must be a finite number > 0");
  if (options.iterations && *options.iterations < 1)
    return Out::failure("iterations must be at least 1");
  return deblur_raw_planes(mosaic_electrons, model, options);
}

}  // namespace flutterscan::imaging
