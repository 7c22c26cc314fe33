#include "session/session_folder.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>

namespace flutterscan::session {
namespace {

namespace fs = std::filesystem;

/// Writes `mat` to `path` through a temporary name in the same folder.
std::string write_png_atomically(const fs::path& path, const cv::Mat& mat) {
  // Built by appending: GCC 12 at -O3 misreports "." + std::string as an overlapping memcpy.
  std::string hidden = ".";
  hidden += path.filename().string();
  hidden += ".tmp.png";
  const fs::path temporary = path.parent_path() / hidden;
  try {
    if (!cv::imwrite(temporary.string(), mat)) return "cannot write '" + path.string() + "'";
  } catch (const cv::Exception& e) {
    return "cannot write '" + path.string() + "': " + e.what();
  }
  std::error_code ec;
  fs::rename(temporary, path, ec);
  if (ec) return "cannot write '" + path.string() + "': " + ec.message();
  return {};
}

}  // namespace

std::string SessionFolder::open(const std::string& path, double disk_budget_mb) {
  path_ = path;
  budget_bytes_ = static_cast<std::uint64_t>(disk_budget_mb * 1024 * 1024);
  std::error_code ec;
  fs::create_directories(fs::path(path) / "frames", ec);
  if (ec) return "cannot create session folder '" + path + "': " + ec.message();
  log_.open(fs::path(path) / "session.jsonl", std::ios::out | std::ios::trunc);
  if (!log_) return "cannot create '" + (fs::path(path) / "session.jsonl").string() + "'";
  return {};
}

void SessionFolder::log(const nlohmann::json& line) {
  std::lock_guard lock(mutex_);
  if (!log_.is_open()) return;
  log_ << line.dump() << '\n';
  log_.flush();
}

std::string SessionFolder::frame_stem(std::uint64_t sequence) {
  char stem[32];
  std::snprintf(stem, sizeof stem, "f%08llu", static_cast<unsigned long long>(sequence));
  return stem;
}

std::string SessionFolder::frame_file(std::uint64_t sequence) {
  return "frames/" + frame_stem(sequence) + ".png";
}

std::string SessionFolder::save_frame(std::uint64_t sequence, const imaging::Image& dn,
                                      const nlohmann::json& descriptor,
                                      const imaging::Plane* fused) {
  const fs::path frames = fs::path(path_) / "frames";
  const std::string stem = frame_stem(sequence);
  Saved saved{sequence, {}, 0};
  auto account = [&](const fs::path& file) {
    std::error_code ec;
    saved.files.push_back(file.string());
    saved.bytes += static_cast<std::uint64_t>(fs::file_size(file, ec));
  };
  // Raw DN: 16-bit containers, OpenCV stores colour as BGR.
  cv::Mat raw;
  if (dn.channel_count() == 3) {
    std::vector<cv::Mat> planes;
    for (int c = 2; c >= 0; --c) {
      cv::Mat p(dn.height(), dn.width(), CV_32F,
                const_cast<float*>(dn.channels[static_cast<std::size_t>(c)].pixels.data()));
      cv::Mat p16;
      p.convertTo(p16, CV_16U);
      planes.push_back(p16);
    }
    cv::merge(planes, raw);
  } else if (dn.channel_count() == 1) {
    cv::Mat p(dn.height(), dn.width(), CV_32F, const_cast<float*>(dn.channels[0].pixels.data()));
    p.convertTo(raw, CV_16U);
  } else {
    return "frame " + std::to_string(sequence) + ": no channels to save";
  }
  const fs::path raw_path = frames / (stem + ".png");
  if (auto p = write_png_atomically(raw_path, raw); !p.empty()) return p;
  account(raw_path);
  const fs::path descriptor_path = frames / (stem + ".json");
  if (auto p =
          write_file((fs::path("frames") / (stem + ".json")).string(), descriptor.dump(2) + "\n");
      !p.empty())
    return p;
  account(descriptor_path);
  if (fused != nullptr) {
    cv::Mat p(fused->height, fused->width, CV_32F, const_cast<float*>(fused->pixels.data()));
    cv::Mat scaled;
    p.convertTo(scaled, CV_16U, 65535.0);  // saturating: reflectance clipped to 0..1
    const fs::path fused_path = frames / (stem + ".fused.png");
    if (auto problem = write_png_atomically(fused_path, scaled); !problem.empty()) return problem;
    account(fused_path);
  }
  std::lock_guard lock(mutex_);
  saved_.push_back(std::move(saved));
  rotate_locked();
  return {};
}

void SessionFolder::rotate_locked() {
  std::uint64_t total = 0;
  for (const auto& s : saved_) total += s.bytes;
  // The newest frame always stays, even alone over the budget.
  while (total > budget_bytes_ && saved_.size() > 1) {
    const Saved& oldest = saved_.front();
    for (const auto& file : oldest.files) {
      std::error_code ec;
      fs::remove(file, ec);
    }
    if (rotation_.frames_rotated == 0) rotation_.first_sequence_rotated = oldest.sequence;
    rotation_.last_sequence_rotated = oldest.sequence;
    ++rotation_.frames_rotated;
    rotation_.bytes_rotated += oldest.bytes;
    total -= oldest.bytes;
    saved_.pop_front();
  }
  rotation_.frames_kept = saved_.size();
  rotation_.bytes_kept = total;
}

std::string SessionFolder::write_file(const std::string& name, const std::string& text) const {
  const fs::path target = fs::path(path_) / name;
  std::string hidden = ".";
  hidden += target.filename().string();
  hidden += ".tmp";
  const fs::path temporary = target.parent_path() / hidden;
  {
    std::ofstream out(temporary, std::ios::binary);
    out << text;
    if (!out) return "cannot write '" + target.string() + "'";
  }
  std::error_code ec;
  fs::rename(temporary, target, ec);
  if (ec) return "cannot write '" + target.string() + "': " + ec.message();
  return {};
}

RotationStats SessionFolder::rotation() const {
  std::lock_guard lock(mutex_);
  return rotation_;
}

void SessionFolder::close() {
  std::lock_guard lock(mutex_);
  if (log_.is_open()) log_.close();
}

}  // namespace flutterscan::session
