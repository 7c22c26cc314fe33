#include "capture/sim_camera.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <deque>
#include <future>
#include <map>
#include <mutex>
#include <numeric>
#include <optional>
#include <random>
#include <sstream>
#include <thread>

#include "capture/backends.hpp"
#include "capture/host_clock.hpp"
#include "device/virtual_controller.hpp"
#include "imaging/capture_descriptor.hpp"
#include "imaging/limits.hpp"
#include "sim/forward_model.hpp"
#include "sim/scene.hpp"

namespace flutterscan::capture {
namespace {

std::string ean13_with_check(std::uint64_t index) {
  char digits[13];
  std::snprintf(digits, sizeof digits, "%012llu",
                static_cast<unsigned long long>(400000000000ULL + index * 7919ULL));
  return std::string(digits, 12) + static_cast<char>('0' + sim::ean13_check_digit(digits));
}

/// The text after the kind: what a decoder should read.
std::string content_of(const std::string& scene) {
  return scene.substr(scene.find(':') + 1);
}

/// The light that actually reached the scene: LED transitions turned into a
/// per-slot code. Slots are the largest step that divides every transition
/// time from the first; the code spans first transition to the last.
struct Lighting {
  bool dark = true;
  LedCode code;
  std::uint64_t start_us = 0;
  std::uint64_t duration_us = 0;
};

Lighting lighting_from(const std::vector<device::LedTransition>& transitions) {
  Lighting light;
  auto first_on = std::find_if(transitions.begin(), transitions.end(),
                               [](const auto& t) { return t.led_mask != 0; });
  if (first_on == transitions.end()) return light;
  const std::uint64_t start = first_on->time_us;
  std::uint64_t end = start;
  std::uint64_t step = 0;
  for (auto it = first_on; it != transitions.end(); ++it) {
    step = std::gcd(step, it->time_us - start);
    end = it->time_us;
  }
  if (transitions.back().led_mask != 0) return light;  // still lit: not a whole sequence
  if (step == 0 || end == start) return light;
  const std::uint64_t slots = (end - start) / step;
  if (slots > static_cast<std::uint64_t>(kMaxSlots)) return light;
  std::vector<std::uint8_t> masks(slots, 0);
  std::uint8_t mask = 0;
  auto it = first_on;
  for (std::uint64_t s = 0; s < slots; ++s) {
    const std::uint64_t t = start + s * step;
    while (it != transitions.end() && it->time_us <= t) mask = (it++)->led_mask;
    masks[s] = mask & 0x7;
  }
  const auto code = LedCode::from_masks(masks, 3);
  if (!code.ok()) return light;
  light.dark = false;
  light.code = code.value();
  light.start_us = start;
  light.duration_us = end - start;
  return light;
}

std::string number_text(double value) {
  std::ostringstream text;
  text.precision(15);
  text << value;
  return text.str();
}

std::string outside(const std::string& key, double value, const std::string& range,
                    const std::string& why = {}) {
  return "camera sim: option " + key + " = " + number_text(value) + " is outside " + range +
         (why.empty() ? "" : ": " + why);
}

class SimCamera final : public CameraSource {
 public:
  SimCamera(device::VirtualController& controller, SimConveyorOptions options)
      : controller_(controller), o_(std::move(options)), rng_(o_.seed) {}

  std::string name() const override { return "sim"; }

  std::string open() override {
    if (auto problem = sim_options_problem(o_); !problem.empty()) return problem;
    if (auto problem = parse_sim_target(o_.target, reflectance_); !problem.empty()) return problem;
    if (!(o_.falloff >= 0 && o_.falloff <= 0.9)) return "camera sim: falloff must be within 0..0.9";
    if (o_.falloff > 0 && reflectance_ < 0)
      return "camera sim: falloff needs the static target (target=white)";
    if (o_.bit_depth < 8 || o_.bit_depth > 16) return "camera sim: bit_depth must be within 8..16";
    if (!(o_.full_well > 0)) return "camera sim: full_well must be > 0";
    if (!(o_.read_noise >= 0)) return "camera sim: read_noise must be >= 0";
    if (!(o_.black_level >= 0 && o_.black_level < std::pow(2.0, o_.bit_depth) - 1))
      return "camera sim: black_level must be within 0..2^bit_depth - 1";
    if (reflectance_ >= 0) return common_checks();  // the belt stands still: no labels to fit
    if (o_.tile_width + 2 * sim::kMinBeltPx > o_.width)
      return "camera sim: tile_width " + std::to_string(o_.tile_width) +
             " does not fit the view width " + std::to_string(o_.width);
    if (!(o_.speed_px_per_s > 0))
      return "camera sim: option speed_px_per_s = " + number_text(o_.speed_px_per_s) +
             " must be > 0 (the labels ride a moving belt; target=white stands still)";
    return common_checks();
  }

  std::string common_checks() const {
    if (o_.ring_frames > 0 && o_.jitter > 0)
      return "camera sim: ring_frames replays identical frames: it needs jitter 0";
    if (o_.crosstalk.size() != 9) return "camera sim: crosstalk needs 9 values (3x3)";
    if (o_.render_threads < 1 || o_.render_threads > 16)
      return "camera sim: render_threads must be within 1..16";
    return {};
  }

  std::string configure(const CameraSettings& wanted) override {
    if (wanted.width) o_.width = *wanted.width;
    if (wanted.height) o_.height = *wanted.height;
    if (wanted.pixel_format && *wanted.pixel_format != PixelFormat::kRgb16)
      return "camera sim: only pixel format rgb16 (12-bit RGB in 16-bit containers)";
    if (wanted.exposure_us && !(*wanted.exposure_us >= 1 && *wanted.exposure_us <= 10e6))
      return outside("exposure_us", *wanted.exposure_us, "1..10000000 us");
    if (wanted.frame_rate_hz && !(*wanted.frame_rate_hz <= 1e6))
      return outside("frame_rate_hz", *wanted.frame_rate_hz, "(0, 1000000] Hz");
    if (wanted.exposure_us) o_.exposure_us = static_cast<std::uint32_t>(*wanted.exposure_us);
    if (wanted.frame_rate_hz && *wanted.frame_rate_hz > 0)
      o_.frame_period_us = static_cast<std::uint32_t>(1e6 / *wanted.frame_rate_hz);
    if (auto problem = open(); !problem.empty()) return problem;
    settings_ = CameraSettings{};
    settings_.width = o_.width;
    settings_.height = o_.height;
    settings_.pixel_format = PixelFormat::kRgb16;
    settings_.exposure_us = o_.exposure_us;
    settings_.gain_db = 0;
    settings_.frame_rate_hz = 1e6 / o_.frame_period_us;
    settings_.trigger = TriggerMode::kFreeRun;
    return {};
  }

  CameraSettings settings() const override { return settings_; }

  FrameFormat format() const override {
    return {o_.width, o_.height, PixelFormat::kRgb16, o_.bit_depth,
            static_cast<std::size_t>(o_.width) * 6};
  }

  std::string start() override {
    if (auto problem = open(); !problem.empty()) return problem;
    if (o_.belt == "print" && belt_print_.empty())
      if (auto problem = render_belt_print(); !problem.empty()) return problem;
    counters_ = {};
    sequence_ = 0;
    delivered_ = 0;
    travel_px_ = 0;
    running_ = true;
    if (o_.ring_frames > 0)
      if (auto problem = prerender_ring(); !problem.empty()) return problem;
    host_start_ns_ = host_now_ns();
    return {};
  }

  FrameWait next_frame(Frame& frame, std::chrono::milliseconds, std::string& error) override {
    if (!running_) return FrameWait::kEnd;
    // Exposures run ahead of delivery by up to `lookahead` frames so that
    // renders overlap on several threads; the virtual clock stays in order.
    const std::size_t lookahead =
        o_.ring_frames > 0 ? 1 : static_cast<std::size_t>(std::max(1, o_.render_threads));
    while (in_flight_.size() < lookahead && (o_.max_frames == 0 || sequence_ < o_.max_frames)) {
      const bool lost = o_.drop_probability > 0 && uniform_(rng_) < o_.drop_probability;
      RenderJob job = expose_one();
      if (lost) {
        ++counters_.frames_dropped;
        continue;
      }
      if (lookahead == 1) {
        std::promise<Rendered> ready;
        ready.set_value(render_job(job));
        in_flight_.push_back(ready.get_future());
      } else {
        in_flight_.push_back(
            std::async(std::launch::async, [this, job] { return render_job(job); }));
      }
    }
    if (in_flight_.empty()) return FrameWait::kEnd;
    Rendered rendered = in_flight_.front().get();
    in_flight_.pop_front();
    if (o_.pace_realtime) {  // delivered at the frame rate, counted from start()
      const std::int64_t due = host_start_ns_ + static_cast<std::int64_t>(delivered_) *
                                                    static_cast<std::int64_t>(o_.frame_period_us) *
                                                    1000;
      const std::int64_t wait = due - host_now_ns();
      if (wait > 0) std::this_thread::sleep_for(std::chrono::nanoseconds(wait));
    }
    ++delivered_;
    if (!rendered.error.empty()) {
      error = rendered.error;
      return FrameWait::kError;
    }
    frame = std::move(rendered.frame);
    frame.host_arrival_ns = host_now_ns();
    ++counters_.frames_delivered;
    counters_.making_ms += rendered.making_ms;
    return FrameWait::kFrame;
  }

  void stop() override {
    running_ = false;
    while (!in_flight_.empty()) {
      in_flight_.front().wait();
      in_flight_.pop_front();
    }
  }
  CameraCounters counters() const override { return counters_; }
  bool live() const override { return o_.pace_realtime; }

 private:
  /// A label's rendered tile and where its symbol lies in it (barcode labels).
  struct LabelTile {
    imaging::Plane plane;
    std::optional<sim::SymbolPlacement> placement;
  };

  /// What one exposure needs rendered.
  struct RenderJob {
    std::uint64_t sequence = 0;
    std::int64_t timestamp_ns = 0;
    Lighting light;
    double travel_at_slot0 = 0;
    double blur = 0;
  };
  struct Rendered {
    Frame frame;
    std::string error;
    double making_ms = 0;  ///< host time it took: rendered, or copied from the ring
  };

  /// The camera's timestamp of controller time `controller_us` (its offset and drift).
  std::int64_t camera_ns(std::uint64_t controller_us) const {
    return o_.clock_offset_ns +
           static_cast<std::int64_t>(static_cast<double>(controller_us) * 1000.0 *
                                     (1.0 + o_.clock_drift_ppm * 1e-6));
  }

  /// One frame period on the virtual clock: strobe, encoder, clock to the next frame.
  RenderJob expose_one() {
    double speed = reflectance_ >= 0 ? 0.0 : o_.speed_px_per_s;  // a static target: belt stopped
    if (o_.jitter > 0) speed *= std::clamp(1.0 + o_.jitter * normal_(rng_), 0.2, 1.8);
    const std::uint64_t begin_us = controller_.now_us();
    const double travel_at_begin = travel_px_;
    controller_.take_led_transitions();
    controller_.set_encoder_velocity(
        static_cast<std::int32_t>(std::lround(speed * o_.counts_per_px)));
    RenderJob job;
    job.timestamp_ns = camera_ns(begin_us);
    controller_.expose(o_.exposure_us);
    const auto transitions = controller_.take_led_transitions();
    const std::uint64_t after_us = controller_.now_us();
    if (after_us < begin_us + o_.frame_period_us)
      controller_.advance_us(begin_us + o_.frame_period_us - after_us);
    const std::uint64_t end_us = controller_.now_us();
    travel_px_ += speed * static_cast<double>(end_us - begin_us) * 1e-6;
    job.sequence = sequence_++;
    job.light = lighting_from(transitions);
    job.travel_at_slot0 =
        travel_at_begin +
        speed * static_cast<double>(job.light.dark ? 0 : job.light.start_us - begin_us) * 1e-6;
    job.blur = job.light.dark ? 0.0 : speed * static_cast<double>(job.light.duration_us) * 1e-6;
    return job;
  }

  /// Ring mode: the ring's frames are rendered (on render_threads) before
  /// start() returns, so that every frame afterwards comes from memory and the
  /// frame rate holds from the first frame on. Only the first is exposed now:
  /// each strobe queues an exposure event on the controller, which holds 16
  /// for the host, so exposing the whole ring here lost every event after the
  /// 16th. The others are exposed as they are delivered (next_frame); the ring
  /// renders them ahead from the first exposure, whose light and blur repeat
  /// (jitter 0) one frame step of clock and belt further on each time.
  std::string prerender_ring() {
    const auto ring = static_cast<std::size_t>(o_.ring_frames);
    const std::size_t count =
        o_.max_frames == 0 ? ring : std::min(ring, static_cast<std::size_t>(o_.max_frames));
    const bool lost = o_.drop_probability > 0 && uniform_(rng_) < o_.drop_probability;
    const std::uint64_t begin_us = controller_.now_us();
    const RenderJob first = expose_one();
    const std::uint64_t step_us = controller_.now_us() - begin_us;
    const double step_px = travel_px_;  // the belt's travel over the first frame step
    std::vector<RenderJob> jobs(count, first);
    for (std::size_t s = 1; s < count; ++s) {
      jobs[s].sequence = s;
      jobs[s].timestamp_ns = camera_ns(begin_us + s * step_us);
      jobs[s].travel_at_slot0 = first.travel_at_slot0 + static_cast<double>(s) * step_px;
    }
    // The samples go to one block, each frame's as soon as it is rendered: a
    // block this large is mapped apart from the heap, so the ring neither
    // takes the frame memory the session warmed before start() nor leaves it
    // so much free heap on the way that the allocator returns it to the system.
    const std::size_t frame_bytes = format().row_bytes * static_cast<std::size_t>(o_.height);
    ring_samples_.assign(count * frame_bytes, 0);
    std::vector<Rendered> rendered(jobs.size());
    std::atomic<std::size_t> next{0};
    std::vector<std::thread> threads;
    for (int t = 0; t < std::max(1, o_.render_threads); ++t)
      threads.emplace_back([&] {
        for (std::size_t i = next++; i < jobs.size(); i = next++) {
          rendered[i] = render_new(jobs[i]);
          std::vector<std::uint8_t>& data = rendered[i].frame.data;
          std::copy_n(data.begin(), std::min(data.size(), frame_bytes),
                      ring_samples_.begin() + static_cast<std::ptrdiff_t>(i * frame_bytes));
          std::vector<std::uint8_t>().swap(data);
        }
      });
    for (auto& t : threads) t.join();
    ring_.clear();
    for (auto& r : rendered) {
      if (!r.error.empty()) return r.error;
      ring_.push_back(std::move(r.frame));
    }
    if (lost) {
      ++counters_.frames_dropped;
    } else {
      std::promise<Rendered> ready;
      ready.set_value(render_job(first));
      in_flight_.push_back(ready.get_future());
    }
    return {};
  }

  /// The frame of `job` with its identity set and nothing drawn yet.
  Frame frame_of(const RenderJob& job) const {
    Frame frame;
    frame.sequence = job.sequence;
    frame.timestamp_ns = job.timestamp_ns;
    frame.format = format();
    return frame;
  }

  /// `job` through the forward model (any thread).
  Rendered render_new(const RenderJob& job) {
    Rendered out;
    out.frame = frame_of(job);
    render(out.frame, job.light, job.travel_at_slot0, job.blur, out.error);
    return out;
  }

  /// `job`'s frame copied from the ring (ring mode).
  Rendered copy_from_ring(const RenderJob& job) const {
    Rendered out;
    out.frame = frame_of(job);
    const std::size_t slot = job.sequence % ring_.size();
    const Frame& stored = ring_[slot];
    const std::size_t frame_bytes = ring_samples_.size() / ring_.size();
    const auto from = ring_samples_.begin() + static_cast<std::ptrdiff_t>(slot * frame_bytes);
    out.frame.data.assign(from, from + static_cast<std::ptrdiff_t>(frame_bytes));
    out.frame.truth = stored.truth;
    out.frame.truth_in_view = stored.truth_in_view;
    out.frame.truth_labels = stored.truth_labels;
    out.frame.descriptor_json = stored.descriptor_json;
    return out;
  }

  /// `job` from the ring (ring mode), else rendered; timed (making_ms).
  Rendered render_job(const RenderJob& job) {
    const std::int64_t start = host_now_ns();
    Rendered out = ring_.empty() ? render_new(job) : copy_from_ring(job);
    out.making_ms = static_cast<double>(host_now_ns() - start) * 1e-6;
    return out;
  }

  imaging::CaptureModel model_for(const Lighting& light, double blur) const {
    imaging::CaptureModel m;
    m.code = light.code;
    m.blur_px = blur;
    m.crosstalk = o_.crosstalk;
    const auto per_bit = imaging::budgeted_led_electrons(light.code, o_.electrons, o_.cap);
    // A pattern that lights fewer than the three LEDs has fewer bits: the rest stay dark.
    m.led_electrons.assign(3, 0.0);
    std::copy_n(per_bit.begin(), std::min<std::size_t>(per_bit.size(), 3), m.led_electrons.begin());
    m.ambient_electrons = {0, 0, 0};
    m.read_noise = o_.read_noise;
    m.full_well = o_.full_well;
    m.bit_depth = o_.bit_depth;
    m.black_level = o_.black_level;
    m.gain = o_.full_well / (std::pow(2.0, o_.bit_depth) - 1.0);
    return m;
  }

  /// The static white card, under light falling off toward the corners.
  void render_target(imaging::Plane& window, int pad) const {
    const double cx = (o_.width - 1) / 2.0, cy = (o_.height - 1) / 2.0;
    const double corner2 = cx * cx + cy * cy;
    for (int y = 0; y < window.height; ++y)
      for (int x = 0; x < window.width; ++x) {
        const double dx = std::clamp(x - pad, 0, o_.width - 1) - cx, dy = y - cy;
        window.at(x, y) =
            static_cast<float>(reflectance_ * (1.0 - o_.falloff * (dx * dx + dy * dy) / corner2));
      }
  }

  bool render(Frame& frame, const Lighting& light, double travel, double blur, std::string& error) {
    const int pad = static_cast<int>(std::ceil(blur)) + 2;
    imaging::Plane window(o_.width + pad, o_.height);
    frame.truth.clear();
    frame.truth_in_view.clear();
    frame.truth_labels.clear();
    if (reflectance_ >= 0)
      render_target(window, pad);
    else if (!render_labels(window, frame, pad, travel, blur, error))
      return false;
    return record(frame, window, pad, light, blur);
  }

  /// The belt and its labels into `window` (`pad` columns upstream of the view),
  /// and the frame's ground truth.
  bool render_labels(imaging::Plane& window, Frame& frame, int pad, double travel, double blur,
                     std::string& error) {
    const double pitch = o_.tile_width + o_.gap;
    for (int x = 0; x < window.width; ++x) {
      const double u = (x - pad) - travel;
      float column_value = -1;
      std::shared_ptr<const LabelTile> tile;
      double k = 0;
      if (u < 0) {
        const double i = std::ceil(-u / pitch) - 1;
        k = u + (i + 1) * pitch;
        if (k < o_.tile_width - 1) {
          tile = tile_for(static_cast<std::uint64_t>(i), error);
          if (!tile) return false;
        }
      }
      if (tile == nullptr) column_value = static_cast<float>(kBelt);
      // The printed belt repeats every belt_print_.width px of belt; it shows
      // wherever the belt does (around a tile's label too).
      const double period = belt_print_.width;
      const double b = belt_print_.empty() ? 0 : std::fmod(std::fmod(u, period) + period, period);
      const int b0 = static_cast<int>(b), b1 = b0 + 1 < belt_print_.width ? b0 + 1 : 0;
      const float g = static_cast<float>(b - b0);
      const int k0 = static_cast<int>(k);
      const float f = static_cast<float>(k - k0);
      for (int y = 0; y < o_.height; ++y) {
        float v = tile == nullptr ? column_value
                                  : tile->plane.at(k0, y) * (1 - f) + tile->plane.at(k0 + 1, y) * f;
        if (!belt_print_.empty() && v == static_cast<float>(kBelt))
          v = belt_print_.at(b0, y) * (1 - g) + belt_print_.at(b1, y) * g;
        window.at(x, y) = v;
      }
    }
    // Labels a deblur can recover whole: the tile stays in view from the first
    // slot to the last, and starts at least one blur length from the upstream
    // edge (whose latent depends on belt outside the frame).
    for (std::uint64_t i = 0;; ++i) {
      const double left = -(static_cast<double>(i) + 1) * pitch + travel;
      if (left + o_.tile_width + blur <= o_.width && left >= blur) {
        frame.truth.push_back(content_of(sim_label_scene(i)));
        std::lock_guard lock(tiles_mutex_);
        if (const auto tile = tiles_.find(i); tile != tiles_.end() && tile->second->placement) {
          const sim::SymbolPlacement& placed = *tile->second->placement;
          TruthLabel t;
          t.value = frame.truth.back();
          t.symbology_id = placed.symbology_id;
          t.module_px = placed.module_px;
          for (int c = 0; c < 4; ++c)
            t.corners[c] = {placed.corners[c][0] + left, placed.corners[c][1]};
          frame.truth_labels.push_back(std::move(t));
        }
      }
      if (left < o_.width && left + o_.tile_width + blur > 0)
        frame.truth_in_view.push_back(content_of(sim_label_scene(i)));
      if (left + o_.tile_width < 0) break;
    }
    return true;
  }

  /// The scene in `window` through the forward model into the frame's bytes and descriptor.
  bool record(Frame& frame, const imaging::Plane& window, int pad, const Lighting& light,
              double blur) {
    imaging::Image dn;
    imaging::CaptureModel model;
    if (light.dark) {
      model = model_for(Lighting{false, LedCode::parse("1", 1).value(), 0, 0}, 0);
      imaging::Image zero;
      for (int c = 0; c < 3; ++c) zero.channels.emplace_back(window.width, window.height);
      dn = sim::record_frame(zero, model, o_.seed * 1'000'003 + frame.sequence);
    } else {
      model = model_for(light, blur);
      dn = sim::record_frame(sim::expected_electrons(window, model), model,
                             o_.seed * 1'000'003 + frame.sequence);
    }
    frame.data.resize(static_cast<std::size_t>(o_.width) * o_.height * 6);
    std::uint8_t* out = frame.data.data();
    for (int y = 0; y < o_.height; ++y)
      for (int x = 0; x < o_.width; ++x)
        for (int c = 0; c < 3; ++c) {
          const auto v = static_cast<std::uint16_t>(dn.channels[c].at(x + pad, y));
          *out++ = static_cast<std::uint8_t>(v & 0xFF);
          *out++ = static_cast<std::uint8_t>(v >> 8);
        }
    nlohmann::json descriptor = imaging::to_descriptor(model);
    descriptor["capture"] = {{"sequence", frame.sequence},
                             {"timestamp_ns", frame.timestamp_ns},
                             {"truth", frame.truth},
                             {"truth_in_view", frame.truth_in_view},
                             {"source", "sim"}};
    frame.descriptor_json = descriptor.dump();
    return true;
  }

  std::shared_ptr<const LabelTile> tile_for(std::uint64_t index, std::string& error) {
    std::lock_guard lock(tiles_mutex_);
    auto found = tiles_.find(index);
    if (found != tiles_.end()) return found->second;
    // Keep the cache small: tiles far behind the belt are gone for good.
    while (tiles_.size() > 8) tiles_.erase(tiles_.begin());
    auto spec = sim::parse_scene(sim_label_scene(index));
    if (!spec.ok()) {
      error = "camera sim: label " + std::to_string(index) + ": " + spec.error();
      return {};
    }
    spec.value().width = o_.tile_width;
    spec.value().height = o_.height;
    spec.value().belt = kBelt;
    const bool linear = spec.value().kind == sim::SceneKind::kCode128 ||
                        spec.value().kind == sim::SceneKind::kEan13;
    spec.value().module_px = linear ? 2.5 : 4;
    auto rendered = sim::render_scene(spec.value());
    if (!rendered.ok()) {
      error = "camera sim: label " + std::to_string(index) + ": " + rendered.error();
      return {};
    }
    LabelTile made{std::move(rendered.value()), std::nullopt};
    if (auto placed = sim::symbol_placement(spec.value()); placed.ok())
      made.placement = std::move(placed.value());
    auto tile = std::make_shared<const LabelTile>(std::move(made));
    tiles_.emplace(index, tile);
    return tile;
  }

  /// The printed belt (option belt=print): kPrintPeriod px of belt, four pieces
  /// of text a band, bands of module 1.5, 2.5 and 3.5 px in turn (a piece at
  /// most 21 characters: 3.5 px modules fill a quarter of the period), ink on
  /// the belt's 0.35.
  std::string render_belt_print() {
    constexpr int kPrintPeriod = 2048;
    static const std::array<std::string, 8> kLines = {
        "FRAGILE THIS SIDE UP", "SHIP TO 4410 RIVER DR", "LOT 2026-11 B 88213",
        "MADE IN EU 24x330 ml", "www.example.com/ret",   "KEEP DRY STACK 4",
        "NET 12.4 kg",          "REF 00713 0800 123"};
    belt_print_ = imaging::Plane(kPrintPeriod, o_.height, static_cast<float>(kBelt));
    int line = 0;
    // Each line in a band of its text's height and 8 px of belt above and below
    // (the last band that does not fit left plain).
    for (int y = 0;; ++line) {
      const double module = 1.5 + (line % 3);
      const int row_height = static_cast<int>(std::lround(module * 20)) + 16;
      if (y + row_height > o_.height) break;
      for (int x = 0; x < kPrintPeriod; x += kPrintPeriod / 4) {
        sim::SceneSpec spec;
        spec.kind = sim::SceneKind::kText;
        spec.content =
            kLines[static_cast<std::size_t>(line * 3 + x / (kPrintPeriod / 4)) % kLines.size()];
        spec.module_px = module;
        spec.width = kPrintPeriod / 4;
        spec.height = row_height;
        spec.paper = kBelt;
        spec.belt = kBelt;
        auto text = sim::render_scene(spec);
        if (!text.ok()) return "camera sim: belt print: " + text.error();
        for (int ty = 0; ty < row_height; ++ty)
          for (int tx = 0; tx < spec.width; ++tx)
            belt_print_.at(x + tx, y + ty) = text.value().at(tx, ty);
      }
      y += row_height;
    }
    return {};
  }

  static constexpr double kBelt = 0.35;
  imaging::Plane belt_print_;  ///< option belt=print; empty: a plain belt

  device::VirtualController& controller_;
  SimConveyorOptions o_;
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  std::normal_distribution<double> normal_{0.0, 1.0};
  CameraSettings settings_;
  double reflectance_ = -1;  ///< the static target's; -1: labels on a moving belt
  CameraCounters counters_;
  std::uint64_t sequence_ = 0;
  std::uint64_t delivered_ = 0;
  double travel_px_ = 0;
  std::int64_t host_start_ns_ = 0;
  bool running_ = false;
  std::mutex tiles_mutex_;
  std::map<std::uint64_t, std::shared_ptr<const LabelTile>> tiles_;
  std::deque<std::future<Rendered>> in_flight_;
  std::vector<Frame> ring_;                 ///< ring mode: each frame but its samples
  std::vector<std::uint8_t> ring_samples_;  ///< ring mode: the frames' samples, one after another
};

template <typename T>
bool parse_number(const std::string& text, T& value) {
  if constexpr (std::is_floating_point_v<T>) {
    try {
      std::size_t used = 0;
      value = static_cast<T>(std::stod(text, &used));
      return used == text.size() && std::isfinite(static_cast<double>(value));
    } catch (...) {
      return false;
    }
  } else {
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    return ec == std::errc() && end == text.data() + text.size();
  }
}

}  // namespace

std::string sim_label_scene(std::uint64_t index) {
  char text[48];
  switch (index % 4) {
    case 0:
      std::snprintf(text, sizeof text, "code128:FS-%05llu", static_cast<unsigned long long>(index));
      return text;
    case 1:
      return "ean13:" + ean13_with_check(index);
    case 2:
      std::snprintf(text, sizeof text, "qr:flutterscan-%05llu",
                    static_cast<unsigned long long>(index));
      return text;
    default:
      std::snprintf(text, sizeof text, "datamatrix:DM%05llu",
                    static_cast<unsigned long long>(index));
      return text;
  }
}

std::string apply_sim_options(const std::vector<std::pair<std::string, std::string>>& options,
                              SimConveyorOptions& o) {
  for (const auto& [key, value] : options) {
    bool ok = true;
    if (key == "width")
      ok = parse_number(value, o.width);
    else if (key == "height")
      ok = parse_number(value, o.height);
    else if (key == "tile_width")
      ok = parse_number(value, o.tile_width);
    else if (key == "gap")
      ok = parse_number(value, o.gap);
    else if (key == "speed_px_per_s")
      ok = parse_number(value, o.speed_px_per_s);
    else if (key == "jitter")
      ok = parse_number(value, o.jitter);
    else if (key == "counts_per_px")
      ok = parse_number(value, o.counts_per_px);
    else if (key == "frame_period_us")
      ok = parse_number(value, o.frame_period_us);
    else if (key == "exposure_us")
      ok = parse_number(value, o.exposure_us);
    else if (key == "electrons")
      ok = parse_number(value, o.electrons);
    else if (key == "cap")
      ok = parse_number(value, o.cap);
    else if (key == "read_noise")
      ok = parse_number(value, o.read_noise);
    else if (key == "drop_probability")
      ok = parse_number(value, o.drop_probability);
    else if (key == "clock_offset_ns")
      ok = parse_number(value, o.clock_offset_ns);
    else if (key == "clock_drift_ppm")
      ok = parse_number(value, o.clock_drift_ppm);
    else if (key == "seed")
      ok = parse_number(value, o.seed);
    else if (key == "max_frames")
      ok = parse_number(value, o.max_frames);
    else if (key == "ring_frames")
      ok = parse_number(value, o.ring_frames);
    else if (key == "render_threads")
      ok = parse_number(value, o.render_threads);
    else if (key == "full_well")
      ok = parse_number(value, o.full_well);
    else if (key == "bit_depth")
      ok = parse_number(value, o.bit_depth);
    else if (key == "black_level")
      ok = parse_number(value, o.black_level);
    else if (key == "falloff")
      ok = parse_number(value, o.falloff);
    else if (key == "target") {
      double reflectance = 0;
      if (auto problem = parse_sim_target(value, reflectance); !problem.empty()) return problem;
      o.target = value;
    } else if (key == "crosstalk") {
      // Nine numbers, row-major (rows: camera channels, columns: LEDs).
      std::vector<double> matrix;
      std::size_t begin = 0;
      while (ok && begin <= value.size()) {
        const std::size_t comma = std::min(value.find(',', begin), value.size());
        double entry = 0;
        ok = parse_number(value.substr(begin, comma - begin), entry) && entry >= 0;
        matrix.push_back(entry);
        begin = comma + 1;
      }
      ok = ok && matrix.size() == 9;
      if (ok) o.crosstalk = matrix;
    } else if (key == "belt") {
      ok = value == "plain" || value == "print";
      if (ok) o.belt = value;
    } else if (key == "pace_realtime") {
      ok = value == "true" || value == "false";
      o.pace_realtime = value == "true";
    } else
      return "camera sim: unknown option '" + key + "'";
    if (!ok) return "camera sim: option " + key + ": '" + value + "' is not a valid value";
  }
  return {};
}

std::string sim_options_problem(const SimConveyorOptions& o) {
  if (!(o.jitter >= 0 && o.jitter <= 0.5)) return outside("jitter", o.jitter, "[0, 0.5]");
  if (!(o.drop_probability >= 0 && o.drop_probability < 1))
    return outside("drop_probability", o.drop_probability, "[0, 1)");
  const std::string side_range = "64.." + std::to_string(imaging::kMaxFrameSidePx) + " px";
  if (o.width < 64 || o.width > imaging::kMaxFrameSidePx)
    return outside("width", o.width, side_range);
  if (o.height < 64 || o.height > imaging::kMaxFrameSidePx)
    return outside("height", o.height, side_range);
  if (static_cast<long long>(o.width) * o.height > imaging::kMaxFramePixels)
    return "camera sim: width x height = " + std::to_string(o.width) + " x " +
           std::to_string(o.height) + " is more than " + std::to_string(imaging::kMaxFramePixels) +
           " pixels";
  // (open() checks that a label's tile fits the view when there are labels.)
  if (o.tile_width < 16 || o.tile_width > imaging::kMaxFrameSidePx)
    return outside("tile_width", o.tile_width,
                   "16.." + std::to_string(imaging::kMaxFrameSidePx) + " px");
  if (o.gap < 0 || o.gap > imaging::kMaxFrameSidePx)
    return outside("gap", o.gap, "0.." + std::to_string(imaging::kMaxFrameSidePx) + " px");
  if (o.frame_period_us < 1 || o.frame_period_us > 60'000'000)
    return outside("frame_period_us", o.frame_period_us, "1..60000000 us");
  if (o.exposure_us < 1 || o.exposure_us > 10'000'000)
    return outside("exposure_us", o.exposure_us, "1..10000000 us");
  if (o.exposure_us >= o.frame_period_us)
    return outside("exposure_us", o.exposure_us,
                   "1.." + std::to_string(o.frame_period_us - 1) + " us",
                   "shorter than frame_period_us = " + std::to_string(o.frame_period_us));
  if (!(o.counts_per_px > 0 && o.counts_per_px <= kMaxSimCountsPerPx))
    return outside("counts_per_px", o.counts_per_px,
                   "(0, " + number_text(kMaxSimCountsPerPx) + "]");
  // The belt moves along the frame's width: over the exposure it may move at most the
  // view's width less one pixel (the longest blur a frame can hold), at any jitter.
  const double longest_blur_px = std::min(static_cast<double>(o.width) - 1, imaging::kMaxBlurPx);
  const double jitter_factor = o.jitter > 0 ? 1.8 : 1.0;  // expose_one's clamp
  const double fastest = longest_blur_px / (o.exposure_us * 1e-6) / jitter_factor;
  if (!(o.speed_px_per_s >= 0 && o.speed_px_per_s <= fastest))
    return outside("speed_px_per_s", o.speed_px_per_s, "[0, " + number_text(fastest) + "] px/s",
                   "over exposure_us = " + std::to_string(o.exposure_us) +
                       (o.jitter > 0 ? " (jittered up to x1.8)" : "") +
                       " the belt may move at most " + number_text(longest_blur_px) +
                       " px, the longest blur of a " + std::to_string(o.width) + " px wide view");
  // The encoder's velocity is a 32-bit count per second.
  if (o.speed_px_per_s * 1.8 * o.counts_per_px > 1e9)
    return "camera sim: speed_px_per_s x counts_per_px = " +
           number_text(o.speed_px_per_s * o.counts_per_px) +
           " counts/s is more than the encoder counts (1e9 counts/s)";
  if (!(o.electrons > 0 && o.electrons <= 1e9))
    return outside("electrons", o.electrons, "(0, 1e9] e-");
  if (!(o.cap > 0 && o.cap <= 1000)) return outside("cap", o.cap, "(0, 1000]");
  if (!(o.full_well > 0 && o.full_well <= 1e9))
    return outside("full_well", o.full_well, "(0, 1e9] e-");
  if (!(o.read_noise >= 0 && o.read_noise <= 1e4))
    return outside("read_noise", o.read_noise, "[0, 10000] e-");
  if (!(std::abs(o.clock_drift_ppm) <= 1e4))
    return outside("clock_drift_ppm", o.clock_drift_ppm, "[-10000, 10000] ppm");
  if (o.clock_offset_ns < 0 || o.clock_offset_ns > 1'000'000'000'000'000'000LL)
    return outside("clock_offset_ns", static_cast<double>(o.clock_offset_ns), "[0, 1e18] ns");
  const double frame_bytes = static_cast<double>(o.width) * o.height * 6;
  if (o.ring_frames < 0 || o.ring_frames * frame_bytes > kMaxSimRingBytes)
    return outside(
        "ring_frames", o.ring_frames,
        "0.." + number_text(std::floor(kMaxSimRingBytes / frame_bytes)),
        "the ring holds every frame (at most " + number_text(kMaxSimRingBytes / 1e9) + " GB)");
  return {};
}

std::string parse_sim_target(const std::string& target, double& reflectance) {
  reflectance = -1;
  if (target == "labels") return {};
  if (target == "white") {
    reflectance = 0.9;
    return {};
  }
  if (target.rfind("white:", 0) == 0 && parse_number(target.substr(6), reflectance) &&
      reflectance > 0 && reflectance <= 1)
    return {};
  reflectance = -1;
  return "camera sim: target must be labels, white or white:REFLECTANCE (0 < R <= 1), not '" +
         target + "'";
}

SimTruth sim_truth(const SimConveyorOptions& options) {
  SimTruth truth;
  truth.crosstalk = options.crosstalk;
  truth.black_level_dn = options.black_level;
  truth.gain_e_per_dn = options.full_well / (std::pow(2.0, options.bit_depth) - 1.0);
  truth.read_noise_e = options.read_noise;
  truth.px_per_count = 1.0 / options.counts_per_px;
  return truth;
}

std::unique_ptr<CameraSource> make_sim_camera(device::VirtualController& controller,
                                              const SimConveyorOptions& options) {
  return std::make_unique<SimCamera>(controller, options);
}

CameraBackend sim_camera_backend() {
  CameraBackend backend;
  backend.scheme = "sim";
  backend.summary =
      "sim: a virtual conveyor lit by the virtual controller (needs --controller sim)";
  backend.create = [](const std::string&, const CameraContext& context, std::string& error) {
    if (context.controller == nullptr) {
      error = "camera 'sim' needs the virtual controller (--controller sim)";
      return std::unique_ptr<CameraSource>();
    }
    SimConveyorOptions options;
    error = apply_sim_options(context.options, options);
    if (!error.empty()) return std::unique_ptr<CameraSource>();
    // The sim's open() only checks its options: a refusal here is bad input (exit 2).
    auto camera = make_sim_camera(*context.controller, options);
    error = camera->open();
    if (!error.empty()) return std::unique_ptr<CameraSource>();
    return camera;
  };
  backend.list = [] {
    CameraInfo info;
    info.spec = "sim";
    info.description = "virtual conveyor camera (always present; needs --controller sim)";
    info.pixel_formats = {"rgb16"};
    info.features = {"exposure", "frame rate", "strobe to controller (slave)"};
    return std::vector<CameraInfo>{info};
  };
  return backend;
}

}  // namespace flutterscan::capture
