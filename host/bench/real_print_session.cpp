#include "bench/real_print_session.hpp"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <stdexcept>

#include "session/frame_model.hpp"
#include "session/frame_processing.hpp"
#include "session/session_clock.hpp"

namespace flutterscan::bench {
namespace {

session::ExposureRecord event(const session::SessionConfig& config, int encoder_counts) {
  session::ExposureRecord e;
  e.frame_counter = 1;
  e.encoder_delta = encoder_counts;
  e.slot_time_us = config.controller.slot_time_us;
  e.slot_count = static_cast<std::uint16_t>(config.controller.parsed_code.length());
  return e;
}

capture::FrameFormat format(int width, int height, int bit_depth) {
  return {width, height, capture::PixelFormat::kRgb16, bit_depth, 0};
}

}  // namespace

session::SessionConfig line_config(double electrons, reader::DecodeArea area,
                                   const session::SecondPassTries& tries, double second_pass_ms,
                                   double decode_ms) {
  session::SessionConfig config;
  config.processing.decode_ms = decode_ms;
  config.optics.electrons = electrons;
  config.processing.decode_area = area;
  config.optics.electrons_given = true;
  config.processing.threads_per_worker = 1;
  config.processing.second_pass_ms = second_pass_ms;
  config.processing.second_pass_tries = tries;
  return config;
}

SessionLine::SessionLine(int width, int height, double blur_px, double electrons,
                         reader::DecodeArea area)
    : SessionLine(line_config(electrons, area), width, height, blur_px) {}

SessionLine::SessionLine(int width, int height, double blur_px, double electrons,
                         reader::DecodeArea area, const session::SecondPassTries& tries,
                         double second_pass_ms, double decode_ms)
    : SessionLine(line_config(electrons, area, tries, second_pass_ms, decode_ms), width, height,
                  blur_px) {}

SessionLine::SessionLine(session::SessionConfig config, int width, int height, double blur_px)
    : config_(std::move(config)), width_(width), height_(height) {
  if (auto problem = session::check_config(config_); !problem.empty())
    throw std::runtime_error("session config: " + problem);
  encoder_counts_ = static_cast<int>(std::lround(blur_px / config_.optics.px_per_count));
  auto model = session::frame_model(event(config_, encoder_counts_), config_.controller.parsed_code,
                                    config_, format(width, height, config_.optics.bit_depth));
  if (!model.ok()) throw std::runtime_error(model.error());
  model_ = std::move(model.value());
}

int SessionRead::windows() const {
  if (log.contains("error")) return 0;
  int n = log.value("decode_windows", 1);
  if (log.contains("second_pass") && log["second_pass"].contains("windows"))
    n += static_cast<int>(log["second_pass"]["windows"].size());
  return n;
}

void SessionLine::at_frame_rate(double fps, int workers) {
  fps_ = fps;
  config_.processing.workers = workers;
}

SessionRead SessionLine::read(const imaging::Image& dn) const {
  session::FrameJob job;
  job.event = event(config_, encoder_counts_);
  job.frame.format = format(width_, height_, config_.optics.bit_depth);
  job.frame.data.resize(static_cast<std::size_t>(width_) * height_ * 6);
  for (int y = 0; y < height_; ++y)
    for (int x = 0; x < width_; ++x)
      for (int c = 0; c < 3; ++c) {
        const auto v = static_cast<std::uint16_t>(
            std::clamp(dn.channels[static_cast<std::size_t>(c)].at(x, y), 0.0f, 65535.0f));
        const std::size_t at = (static_cast<std::size_t>(y) * width_ + x) * 6 + c * 2;
        job.frame.data[at] = static_cast<std::uint8_t>(v & 0xff);
        job.frame.data[at + 1] = static_cast<std::uint8_t>(v >> 8);
      }
  session::WorkerShared shared(config_);
  if (fps_ > 0) {
    shared.second_pass.expect_period_ms(1000 / fps_);
    shared.live_arrivals = true;
    job.frame.host_arrival_ns = session::now_ns();
  }
  session::FrameOutcome out = session::process_frame(job, config_, shared, nullptr);
  SessionRead read;
  if (!out.processed) {  // a NO-READ, said
    std::cerr << "the session did not process a frame: " << out.log.dump() << "\n";
    read.log = std::move(out.log);
    return read;
  }
  reader::BarcodeReadout& readout = read.readout;
  for (const session::Sighting& s : out.sightings)
    if (s.decoded) readout.codes.push_back(s.code);
  for (const auto& logged : out.log.value("unconfirmed", nlohmann::json::array())) {
    reader::DecodedCode code;
    code.text = logged.at("text").get<std::string>();
    code.format = logged.at("format").get<std::string>();
    code.decoder = logged.at("decoder").get<std::string>();
    code.pass = logged.at("pass").get<std::string>();
    readout.unconfirmed.push_back(std::move(code));
  }
  read.log = std::move(out.log);
  return read;
}

}  // namespace flutterscan::bench
