#pragma once
// The session folder (docs/session.md): session.jsonl (one JSON line per
// frame, flushed line by line, never rotated), frames/ (raw frame as 16-bit
// PNG with its capture descriptor, fused latent as 16-bit grey PNG), and the
// final summary.json and report.html. Frame files rotate within a disk
// budget: when the frames/ files exceed it, the oldest frame's files go
// first; what was rotated is counted for the summary.

#include <nlohmann/json.hpp>

#include <cstdint>
#include <deque>
#include <fstream>
#include <mutex>
#include <string>

#include "imaging/image.hpp"

namespace flutterscan::session {

struct RotationStats {
  std::uint64_t frames_rotated = 0;
  std::uint64_t bytes_rotated = 0;
  std::uint64_t first_sequence_rotated = 0;
  std::uint64_t last_sequence_rotated = 0;
  std::uint64_t frames_kept = 0;
  std::uint64_t bytes_kept = 0;
};

class SessionFolder {
 public:
  /// \brief Creates `path` and path/frames and opens session.jsonl; error names the path.
  std::string open(const std::string& path, double disk_budget_mb);
  const std::string& path() const { return path_; }
  /// \brief Appends one line to session.jsonl and flushes it.
  void log(const nlohmann::json& line);
  /// \brief Writes f<sequence>.png (raw DN, `bit_depth` bits in 16-bit containers),
  /// f<sequence>.json (descriptor) and, if given, f<sequence>.fused.png; then
  /// rotates. Error names the file.
  std::string save_frame(std::uint64_t sequence, const imaging::Image& dn,
                         const nlohmann::json& descriptor, const imaging::Plane* fused);
  /// \brief "fNNNNNNNN": the stem of frame `sequence`'s files.
  static std::string frame_stem(std::uint64_t sequence);
  /// \brief "frames/fNNNNNNNN.png": the raw frame's path in the folder.
  static std::string frame_file(std::uint64_t sequence);
  /// \brief Writes `name` in the folder atomically.
  std::string write_file(const std::string& name, const std::string& text) const;
  RotationStats rotation() const;
  /// \brief Closes session.jsonl.
  void close();

 private:
  struct Saved {
    std::uint64_t sequence;
    std::vector<std::string> files;
    std::uint64_t bytes;
  };
  void rotate_locked();

  std::string path_;
  std::uint64_t budget_bytes_ = 0;
  std::ofstream log_;
  mutable std::mutex mutex_;
  std::deque<Saved> saved_;
  RotationStats rotation_;
};

}  // namespace flutterscan::session
