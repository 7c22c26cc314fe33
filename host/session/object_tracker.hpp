#pragma once
// Objects on the belt: the same label seen in several frames is one object.
// Positions are belt coordinates from the encoder: u = p - travel, p the
// label's position along the motion in the frame (mirrored for -x / -y so
// that objects always move toward larger p) and travel the belt's motion
// since the session began, both in image pixels. A sighting within
// `match_px` of an active object's u is that object. An object is finished
// once it has left the view (u + travel beyond the frame plus `match_px`) or
// has not been seen for `max_unseen_frames` frames; then it gets its result:
// the value read most often, or NO-READ.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "reader/barcode_reader.hpp"

namespace flutterscan::session {

/// \brief The frame a sighting was made in: when, on which trigger, with what
/// blur, how long its decode took and where its files were kept.
struct SightingFrame {
  std::uint64_t sequence = 0;  ///< the camera's frame number
  std::int64_t camera_ns = 0;  ///< the camera's timestamp
  std::int64_t utc_ms = 0;     ///< host wall clock (UTC) when the frame arrived, ms since 1970
  std::uint32_t exposure_counter = 0;     ///< the controller's exposure event
  std::int32_t encoder_delta = 0;         ///< encoder counts during the exposure
  double travel_px = 0;                   ///< belt travel at the trigger since the session began
  double blur_px = 0;                     ///< the blur the deblur used
  std::optional<double> encoder_blur_px;  ///< motion refinement: the encoder's blur
  std::optional<double> refined_blur_px;  ///< and the blur refined on the frame
  double decode_ms = 0;                   ///< the frame's decode step
  std::string kept_frame;  ///< "frames/fNNNNNNNN.png" when the frame's files were kept
};

/// \brief A label seen in one frame.
struct Sighting {
  double position_px = 0;  ///< centre along the motion in the frame (mirrored for -x / -y)
  double across_px = 0;    ///< centre across the motion in the frame
  bool decoded = false;
  std::string value;         ///< when decoded
  std::string format;        ///< when decoded
  reader::DecodedCode code;  ///< when decoded: identifier, corners, module size, quality
  SightingFrame frame;
};

/// \brief One object's result.
struct ObjectResult {
  std::uint64_t id = 0;
  double belt_px = 0;                             ///< u at its last sighting
  std::uint64_t first_frame = 0, last_frame = 0;  ///< camera sequence numbers
  int frames_seen = 0;
  int frames_decoded = 0;
  std::string value;  ///< most frequent value; empty = NO-READ
  std::string format;
  std::map<std::string, int> values;  ///< every value read and how often (a conflict if > 1)
  /// The sighting the record reports: of `value`, the one with the best grade
  /// (the first of equal grades); for a NO-READ, the last sighting.
  Sighting best;
  /// \brief frames_decoded / frames_seen.
  double decode_rate() const { return frames_seen > 0 ? double(frames_decoded) / frames_seen : 0; }
  bool read() const { return !value.empty(); }
};

class ObjectTracker {
 public:
  ObjectTracker(double view_length_px, double match_px, int max_unseen_frames = 30)
      : view_(view_length_px), match_px_(match_px), max_unseen_(max_unseen_frames) {}

  /// \brief The sightings of one frame (frames in capture order; `frame_index`
  /// counts every frame processed, `sequence` is the camera's number).
  void observe(std::uint64_t frame_index, std::uint64_t sequence, double travel_px,
               const std::vector<Sighting>& sightings);
  /// \brief Objects that left the view or went unseen too long, finished now.
  std::vector<ObjectResult> take_finished();
  /// \brief Every object still active (end of session).
  std::vector<ObjectResult> finish_all();

 private:
  struct Active {
    ObjectResult result;
    std::uint64_t last_index = 0;
    std::map<std::string, Sighting> best_read;  ///< by value
  };
  static ObjectResult finished(Active& active);

  double view_;
  double match_px_;
  int max_unseen_;
  std::uint64_t next_id_ = 1;
  std::uint64_t last_index_ = 0;
  double travel_ = 0;
  std::vector<Active> active_;
};

}  // namespace flutterscan::session
