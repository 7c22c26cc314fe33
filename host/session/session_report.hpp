#pragma once
// report.html: one self-contained page (no external resources, no script;
// pictures and charts are data URIs) for the people on the line. Its first
// screen says how the session went in words: the read rate, NO-READs and
// drops, the figures that matter, and what went wrong with what to do about it
// (report_findings.hpp). Then the NO-READs, before/after pictures, throughput
// and latency histograms and the code's spectrum, the objects (the first rows,
// the rest folded), and every figure named in words. Charts are drawn with
// host/plot into DIR/charts/ and embedded.

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "flutterscan/common/led_code.hpp"
#include "session/object_tracker.hpp"
#include "session/value_distribution.hpp"

namespace flutterscan::session {

/// \brief A before/after pair: PNG bytes of the raw frame (display-scaled) and the fused latent.
struct Preview {
  std::uint64_t sequence = 0;
  std::string caption;
  std::vector<std::uint8_t> before;  ///< encoded picture (PNG, or JPEG where asked)
  std::vector<std::uint8_t> after;
};

struct ReportInputs {
  nlohmann::json summary;
  std::vector<ObjectResult> objects;  ///< the latest (summary.json's object_results)
  std::vector<Preview> previews;
  ValueDistribution latency_ms;         ///< per processed frame: arrival to result
  ValueDistribution frames_per_second;  ///< processed frames per second, each span of the run
  LedCode code;
};

/// \brief Standard base64 of `bytes`.
std::string base64(const std::vector<std::uint8_t>& bytes);

/// \brief Writes DIR/report.html (atomically) and its charts under DIR/charts/;
/// error names the file that failed.
std::string write_report(const std::string& folder, const ReportInputs& inputs);

}  // namespace flutterscan::session
