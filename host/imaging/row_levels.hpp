#pragma once
// Row levels: per row and channel, the row's sum and how far its samples stray
// from the row's mean, stretch by stretch. JointWiener's flat-row test and the
// noise level of a channel are made of them. The session's conversion makes
// them while each row it writes is still in cache (capture/frame_pixels.hpp),
// and the motion frame carries them (MotionFrame::row_levels), so the deblur
// need not read the frame's flat rows again: on a belt, most of them.

#include <cstddef>
#include <span>
#include <vector>

#include "imaging/image.hpp"

namespace flutterscan::imaging {

/// \brief Stretches of a row judged apart from each other (the last takes the
/// remainder). The coded blur keeps print's variance but spreads it over the
/// code's lit slots (about 1/17 of it per sample at 52 slots): a 100-px code of
/// 25% and 75% reflectance at 300 e- lifts its stretch's mean square about 2
/// noise variances above the noise, where the whole row's would move 0.1; print
/// of +-12% there (0.5 above) is the limit, and is filled as flat.
inline constexpr std::size_t kFlatRowStretch = 128;

/// \brief One row of one channel.
struct RowLevel {
  /// The samples' sum (imaging::lane_sum).
  float sum = 0;
  /// The largest, over the row's stretches, mean square about the row's mean.
  double worst_mean_square = 0;
  float mean(std::size_t width) const { return sum / static_cast<float>(width); }
};

/// \brief The level of one row (at least 2 samples; fewer give zeros).
RowLevel row_level(std::span<const float> row);

/// \brief Every row's level in every channel of one image.
class RowLevels {
 public:
  RowLevels() = default;
  /// \brief Room for `channels` x `rows` levels of rows `width` samples long, all zero.
  RowLevels(int channels, int rows, int width);
  /// \brief The levels of every row of `image`.
  static RowLevels of(const Image& image);

  void set(int channel, int row, RowLevel level) { levels_[index(channel, row)] = level; }
  const RowLevel& at(int channel, int row) const { return levels_[index(channel, row)]; }
  /// \brief Whether these are levels for `channels` planes of `width` x `rows`.
  bool fits(int channels, int rows, int width) const {
    return !levels_.empty() && channels_ == channels && rows_ == rows && width_ == width;
  }
  bool empty() const { return levels_.empty(); }
  /// \brief The mean over every `step`-th row of channel c (from row 0): the
  /// same value as noise_level_mean(plane) makes with step 4 (capture_model.hpp).
  double mean_of_rows(int channel, int step) const;

 private:
  std::size_t index(int channel, int row) const {
    return static_cast<std::size_t>(channel) * static_cast<std::size_t>(rows_) +
           static_cast<std::size_t>(row);
  }
  int channels_ = 0, rows_ = 0, width_ = 0;
  std::vector<RowLevel> levels_;  ///< channel-major
};

}  // namespace flutterscan::imaging
