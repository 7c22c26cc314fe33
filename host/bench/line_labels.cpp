#include "bench/line_labels.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "bench/real_print_session.hpp"
#include "imaging/exposure_timeline.hpp"
#include "imaging/motion_psf.hpp"
#include "sim/forward_model.hpp"
#include "sim/pixel_integration.hpp"
#include "sim/timeline_forward.hpp"

namespace flutterscan::bench {
namespace {

constexpr int kFine = sim::kSimSupersample;
constexpr double kBelt = 0.35;  // sim::SceneSpec's belt
constexpr int kMarginPx = 8;    // belt beyond the blur, each side

std::string random_content(sim::SceneKind kind, std::mt19937_64& rng) {
  static constexpr char kChars[] = "ABCDEFGHJKLMNPQRSTUVWXYZ0123456789";
  const int length = kind == sim::SceneKind::kCode128 ? 6 : 8;
  std::uniform_int_distribution<int> pick(0, static_cast<int>(sizeof kChars) - 2);
  std::string text;
  for (int i = 0; i < length; ++i) text += kChars[pick(rng)];
  return text;
}

/// `fine` with `left` fine columns of belt before it and `right` after it.
imaging::Plane padded(const imaging::Plane& fine, int left, int right, int first_row, int rows) {
  imaging::Plane out(fine.width + left + right, rows, static_cast<float>(kBelt));
  for (int y = 0; y < rows; ++y) {
    const auto src = fine.row(first_row + y);
    std::copy(src.begin(), src.end(), out.row(y).begin() + left);
  }
  return out;
}

}  // namespace

std::vector<double> line_slot_boundaries(int slots, double blur_px, double speed_ratio,
                                         double jitter_rms, std::uint64_t seed) {
  const auto edges = imaging::accelerating_slot_edges(slots, blur_px, speed_ratio);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> step(static_cast<std::size_t>(slots));
  double total = 0;
  for (int t = 0; t < slots; ++t) {
    const auto i = static_cast<std::size_t>(t);
    step[i] = (edges[i + 1] - edges[i]) * std::max(0.0, 1.0 + jitter_rms * normal(rng));
    total += step[i];
  }
  std::vector<double> out(static_cast<std::size_t>(slots) + 1, 0.0);
  const double scale = total > 0 ? blur_px / total : 0.0;
  for (std::size_t t = 0; t < step.size(); ++t) out[t + 1] = out[t] + step[t] * scale;
  return out;
}

LabelLine LabelLine::make(sim::SceneKind kind, double module_px, int contents, std::uint64_t seed) {
  LabelLine line;
  line.kind_ = kind;
  line.seed_ = seed;
  std::mt19937_64 rng(seed);
  const bool linear = kind == sim::SceneKind::kCode128;
  for (int i = 0; i < contents; ++i) {
    sim::SceneSpec spec;
    spec.kind = kind;
    spec.content = random_content(kind, rng);
    spec.module_px = module_px;
    // Big enough for the label: Code 128 of 6 characters is at most 121 modules
    // with its quiet zones, a Data Matrix of 8 at most 18; grown until it fits.
    const double modules = linear ? 121 : 18;
    spec.width = static_cast<int>(std::ceil(modules * module_px)) + 2 * sim::kMinBeltPx + 2;
    spec.height =
        linear ? static_cast<int>(std::ceil(0.3 * spec.width)) + 2 * sim::kMinBeltPx : spec.width;
    for (int attempt = 0;; ++attempt) {
      auto rendered = sim::render_scene(spec, kFine);
      if (rendered.ok()) {
        line.labels_.push_back({spec.content, std::move(rendered.value())});
        break;
      }
      if (attempt == 6) {
        line.error_ = rendered.error();
        return line;
      }
      spec.width = spec.width * 5 / 4;
      spec.height = spec.height * 5 / 4;
    }
  }
  return line;
}

int LabelLine::frame_width(double blur_px) const {
  const int label = labels_.empty() ? 0 : labels_.front().fine.width / kFine;
  return label + 2 * (static_cast<int>(std::ceil(blur_px)) + kMarginPx) + 1;
}

LabelRead LabelLine::read(const LinePath& path, double blur_px, const LineMotion& motion,
                          std::uint64_t label) const {
  if (labels_.empty()) return {};
  std::mt19937_64 rng(seed_ * 0x9E3779B97F4A7C15ULL + label * 0xBF58476D1CE4E5B9ULL + 1);
  const Label& shown = labels_[label % labels_.size()];
  std::uniform_int_distribution<int> phase_pick(0, kFine - 1);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const int phase = phase_pick(rng);
  const double speed_ratio = 1 + motion.speed_change * unit(rng);
  const double encoder = 1 + motion.encoder_error * unit(rng);
  const std::uint64_t jitter_seed = rng();
  const std::uint64_t noise_seed = rng();

  const int width = frame_width(blur_px);
  const int height = shown.fine.height / kFine;
  // The truth: the line's camera (the session's own model of it) and the belt's
  // motion slot by slot.
  imaging::CaptureModel truth = SessionLine(path.config, width, height, blur_px).model();
  truth.blur_px = blur_px;
  const auto boundaries = line_slot_boundaries(truth.code.length(), truth.blur_px, speed_ratio,
                                               motion.jitter_rms, jitter_seed);
  const auto segments = imaging::segments_from_boundaries(truth.code, boundaries);

  // The whole label on the belt, wholly in view: a blur's travel and a margin of
  // belt upstream (within a blur of the upstream edge the latent also holds
  // what was outside the frame, and the session leaves a label there to the
  // frame in which it has come further into view) and downstream for the blur
  // to run onto. The motion is along the rows, so each camera row is the blur
  // of its own fine rows alone: a row like one already exposed (a linear
  // label's rows of bars, of paper, of belt) is copied, not exposed again.
  const int around = kFine * (static_cast<int>(std::ceil(truth.blur_px)) + kMarginPx);
  const int left = around + phase;
  const int right = around + kFine - phase;
  imaging::Image expected;
  std::vector<std::pair<int, imaging::Image>> exposed;  // first camera row, its exposure
  for (int y = 0; y < height; ++y) {
    const auto same_fine_rows = [&](int other) {
      for (int f = 0; f < kFine; ++f) {
        const auto a = shown.fine.row(y * kFine + f);
        const auto b = shown.fine.row(other * kFine + f);
        if (!std::equal(a.begin(), a.end(), b.begin())) return false;
      }
      return true;
    };
    auto match = std::find_if(exposed.begin(), exposed.end(),
                              [&](const auto& e) { return same_fine_rows(e.first); });
    if (match == exposed.end()) {
      const auto rows = padded(shown.fine, left, right, y * kFine, kFine);
      exposed.emplace_back(y, sim::expected_electrons_timeline(rows, truth, segments, kFine));
      match = std::prev(exposed.end());
    }
    if (expected.channels.empty())
      expected.channels.assign(match->second.channels.size(), imaging::Plane(width, height));
    for (std::size_t c = 0; c < expected.channels.size(); ++c) {
      const auto from = match->second.channels[c].row(0);
      std::copy(from.begin(), from.end(), expected.channels[c].row(y).begin());
    }
  }
  const auto dn = sim::record_frame(expected, truth, noise_seed);

  // What the session knows: the encoder's blur at constant speed.
  SessionLine session(path.config, width, height, blur_px * encoder);
  if (path.fps > 0) session.at_frame_rate(path.fps, path.config.processing.workers);
  const SessionRead seen = session.read(dn);
  LabelRead out;
  for (const auto& code : seen.readout.codes) out.read |= code.text == shown.content;
  if (const auto times = seen.log.find("times_ms"); times != seen.log.end())
    for (const auto& [stage, ms] : times->items()) out.frame_ms += ms.get<double>();
  return out;
}

}  // namespace flutterscan::bench
