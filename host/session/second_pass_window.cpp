#include "session/second_pass_window.hpp"

#include <algorithm>
#include <cmath>

#include "reader/code_measure.hpp"

namespace flutterscan::session {
namespace {

/// Beyond the blur, what the crop adds at each end along the motion: the
/// latent within one blur of a crop's ends is not determined by the crop's
/// samples (docs/algorithms.md, borders), and the periodic extension rings a
/// little further.
constexpr int kCropSlack = 16;

/// Whether camera row `y` lies in the rows of linear code `code` (its corners'
/// rows, widened by 4 px): the rows ZXing reads it on, with their quiet zones
/// and the paper beside them.
bool on_code_rows(const reader::DecodedCode& code, double y) {
  const auto [y0, y1] = reader::corner_rows(code);
  return y >= y0 - 4 && y <= y1 + 4;
}

}  // namespace

bool in_window(const reader::DecodeWindow& w, double x, double y) {
  return x >= w.x && x < w.x + w.width && y >= w.y && y < w.y + w.height;
}

SecondPassWindow::SecondPassWindow(const SecondPassFrame& frame, const reader::LabelRegion& run,
                                   const reader::ReaderOptions& options,
                                   reader::BarcodeReadout& readout, BeltReads& reads)
    : frame_(frame), options_(options), readout_(readout), reads_(reads) {
  const imaging::MotionFrame& electrons = frame.electrons;
  const int along = electrons.along(), lines = electrons.lines();
  const int blur = static_cast<int>(std::ceil(frame.model.blur_px)) + 1;
  keep0_ = std::max(0, run.begin - kWindowMargin);
  keep1_ = std::min(along, run.end + kWindowMargin);
  c0_ = std::max(0, keep0_ - blur - kCropSlack);
  c1_ = std::min(along, keep1_ + blur + kCropSlack);
  const bool rows_known = run.rows_measured();
  r0_ = rows_known ? std::max(0, run.across_begin - kWindowMargin) : 0;
  r1_ = rows_known ? std::min(lines, run.across_end + kWindowMargin) : lines;
  if (c1_ - c0_ <= blur || r1_ <= r0_) return;
  const bool along_x = imaging::moves_along_x(electrons.direction());
  window_ = reader::decode_windows({&run, 1}, along_x ? along : lines, along_x ? lines : along,
                                   electrons.direction(), kWindowMargin)[0];
  imaging::Image channels;
  for (int c = 0; c < electrons.channel_count(); ++c)
    channels.channels.push_back(electrons.channel(c).part(c0_, r0_, c1_, r1_));
  // The crop is in the motion frame already (+x); its samples passed the frame's checks.
  auto made = imaging::MotionFrame::make(std::move(channels), imaging::Direction::kPlusX);
  if (!made.ok()) return;
  crop_ = std::move(made.value());
  first_ = imaging::Plane::uninitialised(c1_ - c0_, r1_ - r0_);
  for (int y = r0_; y < r1_; ++y)
    for (int n = keep0_; n < keep1_; ++n)
      first_.at(n - c0_, y - r0_) = frame.motion_latent.at(n, y);
  for (const reader::DecodedCode& c : readout.codes)
    if (in_window(window_, c.centre_x, c.centre_y)) held_.push_back(c);
}

std::size_t SecondPassWindow::pixels() const {
  return static_cast<std::size_t>(c1_ - c0_) * static_cast<std::size_t>(r1_ - r0_);
}

const imaging::Plane& SecondPassWindow::camera() const {
  return frame_.camera_latent != nullptr ? *frame_.camera_latent : frame_.motion_latent;
}

void SecondPassWindow::paste(const imaging::Plane& latent,
                             std::span<const reader::DecodedCode> codes) {
  const int along = frame_.electrons.along();
  const imaging::Direction direction = frame_.electrons.direction();
  for (int y = r0_; y < r1_; ++y)
    for (int n = keep0_; n < keep1_; ++n) {
      const auto [x, cy] = imaging::camera_point(direction, n, y, along);
      if (!codes.empty() && std::none_of(codes.begin(), codes.end(),
                                         [&](const auto& c) { return on_code_rows(c, cy); }))
        continue;
      const float v = latent.at(n - c0_, y - r0_);
      frame_.motion_latent.at(n, y) = v;
      if (frame_.camera_latent != nullptr) frame_.camera_latent->at(x, cy) = v;
    }
}

std::vector<reader::DecodedCode> SecondPassWindow::read(int independent_apart,
                                                        const std::string& symbologies,
                                                        double turn_rad) {
  reader::DecodeWindow window = window_;
  window.independent_apart = independent_apart;
  reader::BarcodeReadout again =
      turn_rad == 0
          ? reader::read_barcodes(camera(), symbologies, options_.try_rotate, {&window, 1})
          : reader::read_barcodes_turned(camera(), window, turn_rad, symbologies,
                                         options_.try_rotate);
  for (reader::DecodedCode& code : again.unconfirmed)
    if (std::none_of(readout_.unconfirmed.begin(), readout_.unconfirmed.end(),
                     [&](const auto& c) { return reader::same_symbol(c, code); }))
      readout_.unconfirmed.push_back(std::move(code));
  held_read_ = std::all_of(held_.begin(), held_.end(), [&](const reader::DecodedCode& h) {
    return std::any_of(again.codes.begin(), again.codes.end(),
                       [&](const reader::DecodedCode& c) { return reader::same_symbol(c, h); });
  });
  std::erase_if(again.codes, [&](const reader::DecodedCode& code) { return holds(code); });
  return std::move(again.codes);
}

std::vector<std::string> SecondPassWindow::take(std::vector<reader::DecodedCode> codes,
                                                const std::string& pass) {
  const imaging::Direction direction = frame_.electrons.direction();
  const bool along_x = imaging::moves_along_x(direction);
  const int along = frame_.electrons.along(), lines = frame_.electrons.lines();
  std::vector<std::string> texts;
  for (reader::DecodedCode& code : codes) {
    code.pass = pass;
    texts.push_back(code.text);
    linear_taken_ |= reader::is_linear_format(code.format);
    reads_.add(belt_box(code, direction, along_x ? along : lines, along_x ? lines : along,
                        frame_.travel_px));
    readout_.codes.push_back(std::move(code));
  }
  read_values_.insert(read_values_.end(), texts.begin(), texts.end());
  return texts;
}

std::vector<std::string> SecondPassWindow::read_and_take(const std::string& pass,
                                                         int independent_apart,
                                                         const std::string& symbologies,
                                                         double turn_rad) {
  return take(read(independent_apart, symbologies, turn_rad), pass);
}

bool SecondPassWindow::holds(const reader::DecodedCode& code) const {
  return std::any_of(readout_.codes.begin(), readout_.codes.end(),
                     [&](const reader::DecodedCode& c) { return reader::same_symbol(c, code); });
}

bool SecondPassWindow::linear_read() const {
  return linear_taken_ || std::any_of(held_.begin(), held_.end(), [](const auto& c) {
           return reader::is_linear_format(c.format);
         });
}

}  // namespace flutterscan::session
