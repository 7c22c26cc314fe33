#include "session/session_report.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "codes/spectrum.hpp"
#include "plot/line_chart.hpp"
#include "session/read_record.hpp"
#include "session/report_findings.hpp"

namespace flutterscan::session {
namespace {

namespace fs = std::filesystem;

std::string escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::vector<std::uint8_t> read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// A histogram of `values` in `bins` bins over their range, as a step line:
/// bin edges on x, counts on y.
plot::Series histogram(const ValueDistribution& values, int bins, const std::string& label,
                       plot::Rgb colour) {
  plot::Series s;
  s.label = label;
  s.colour = colour;
  s.line_width = 2;
  if (values.count() == 0) return s;
  const double lo = values.min();
  const double hi = values.max() > lo ? values.max() : lo + 1;
  const double width = (hi - lo) / bins;
  const std::vector<std::uint64_t> counts = values.histogram(bins);
  s.x.push_back(lo);
  s.y.push_back(0);
  for (int b = 0; b < bins; ++b) {
    s.x.push_back(lo + b * width);
    s.y.push_back(static_cast<double>(counts[static_cast<std::size_t>(b)]));
    s.x.push_back(lo + (b + 1) * width);
    s.y.push_back(static_cast<double>(counts[static_cast<std::size_t>(b)]));
  }
  s.x.push_back(hi);
  s.y.push_back(0);
  return s;
}

std::string image_tag(const std::vector<std::uint8_t>& png, const std::string& alt) {
  return "<img alt=\"" + escape(alt) + "\" src=\"data:image/png;base64," + base64(png) + "\">";
}

/// The summary's figures in words, in the order the report lists them; `percent`: a
/// share shown as a percentage.
struct FigureName {
  const char* key;
  const char* words;
  bool percent = false;
};
constexpr FigureName kFigureNames[] = {
    {"camera", "Camera"},
    {"controller", "Controller"},
    {"code", "Code"},
    {"method", "Deblur method"},
    {"frame_size", "Frame size"},
    {"duration_s", "Duration (s)"},
    {"stopped_by", "Stopped by"},
    {"frames_captured", "Frames captured"},
    {"frames_processed", "Frames processed"},
    {"frames_dropped", "Frames dropped (processing behind)"},
    {"frames_failed", "Frames that failed"},
    {"frames_without_event", "Frames without an exposure event"},
    {"events_without_frame", "Exposures without a frame"},
    {"camera_frames_lost", "Frames the camera lost"},
    {"objects", "Objects"},
    {"objects_read", "Objects read"},
    {"object_read_rate", "Read rate", true},
    {"mean_decode_rate_per_object", "Frames read per object (mean share)", true},
    {"fps", "Frames per second"},
    {"latency_ms_p50", "Latency, median (ms)"},
    {"latency_ms_p99", "Latency, 99th percentile (ms)"},
    {"clock_drift_ppm", "Camera against controller clock (ppm)"},
};

std::string figure_text(const nlohmann::json& value, bool percent) {
  if (value.is_string()) return value.get<std::string>();
  if (percent && value.is_number()) {
    char text[32];
    std::snprintf(text, sizeof text, "%.1f%%", 100 * value.get<double>());
    return text;
  }
  return value.dump();
}

/// Rows of the per-object table shown before the rest is folded away.
constexpr std::size_t kObjectRowsShown = 20;

void object_row(std::ostringstream& html, const ObjectResult& o) {
  const nlohmann::json r = read_record(o);
  html << "<tr" << (o.read() ? "" : " class=\"noread\"") << "><td>" << o.id << "</td><td>"
       << (o.read() ? "READ" : "NO-READ") << "</td><td style=\"text-align:left\">"
       << escape(o.value) << "</td><td>" << escape(o.format) << "</td><td>"
       << escape(r.value("symbology_id", "")) << "</td><td>" << o.frames_decoded << " / "
       << o.frames_seen << "</td><td>"
       << (r.contains("quality") && r["quality"].contains("grade")
               ? escape(r["quality"]["grade"].get<std::string>())
               : "")
       << "</td><td>" << (r.contains("module_px") ? escape(r["module_px"].dump()) : "")
       << "</td><td>" << std::lround(o.belt_px) << "</td><td>" << escape(r.value("time", ""))
       << "</td><td>" << escape(r.value("frame_file", "")) << "</td></tr>\n";
}

void object_table(std::ostringstream& html, const std::vector<const ObjectResult*>& objects) {
  html << "<table><tr><th>object</th><th>result</th><th>value</th><th>format</th>"
       << "<th>identifier</th><th>frames read / seen</th><th>grade (indicative)</th>"
       << "<th>module px</th><th>belt px</th><th>time (UTC)</th><th>kept frame</th></tr>\n";
  for (const ObjectResult* o : objects) object_row(html, *o);
  html << "</table>\n";
}

/// The first kObjectRowsShown of `objects` as a table, the rest folded under `more`.
void folded_object_table(std::ostringstream& html, const std::vector<const ObjectResult*>& objects,
                         const std::string& more) {
  const std::size_t shown = std::min(objects.size(), kObjectRowsShown);
  object_table(html, {objects.begin(), objects.begin() + static_cast<std::ptrdiff_t>(shown)});
  if (objects.size() > shown) {
    html << "<details><summary>" << objects.size() - shown << " " << escape(more) << "</summary>\n";
    object_table(html, {objects.begin() + static_cast<std::ptrdiff_t>(shown), objects.end()});
    html << "</details>\n";
  }
}

struct Chart {
  std::string title;
  std::string file;
};

std::string report_page(const ReportInputs& in, const std::vector<Chart>& charts) {
  std::ostringstream html;
  const auto& s = in.summary;
  const auto objects = s.value("objects", std::uint64_t{0});
  const auto read = s.value("objects_read", std::uint64_t{0});
  const auto dropped = s.value("frames_dropped", std::uint64_t{0});
  const double rate = s.value("object_read_rate", 0.0);
  const std::vector<Finding> findings = report_findings(s);
  const char* verdict = findings.front().severity == Finding::Severity::kProblem   ? "problem"
                        : findings.front().severity == Finding::Severity::kWarning ? "warning"
                                                                                   : "good";
  html << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
       << "<title>flutterscan session report</title><style>"
       << "body{font-family:sans-serif;margin:2em;max-width:1200px;color:#222}"
       << "table{border-collapse:collapse;margin-bottom:.5em}td,th{border:1px solid #bbb;"
          "padding:2px 8px;text-align:right}th{background:#eee}.noread{background:#fdd}"
       << "img{max-width:100%;border:1px solid #ccc}.sub{color:#555;margin-top:-.5em}"
       << ".pair{display:grid;grid-template-columns:1fr 1fr;gap:8px;margin-bottom:1em}"
       << ".verdict{font-size:1.5em;padding:.5em .8em;border-radius:6px;margin:1em 0}"
       << ".verdict.good{background:#d8f0d8}.verdict.warning{background:#fbeec8}"
       << ".verdict.problem{background:#f7d4d4}"
       << ".cards{display:flex;flex-wrap:wrap;gap:8px}.card{border:1px solid #ccc;"
          "border-radius:6px;padding:.4em .8em;min-width:9em}.card b{font-size:1.6em;"
          "display:block}"
       << ".findings li{margin:.4em 0}.findings .problem b{color:#a00}"
          ".findings .warning b{color:#a60}.findings .good b{color:#070}"
       << ".todo{color:#444}details{margin:.5em 0}summary{cursor:pointer;color:#036}"
       << "</style></head><body>\n<h1>flutterscan session report</h1>\n";
  html << "<p class=\"sub\">" << escape(s.value("camera", "")) << " &middot; "
       << escape(s.value("controller", "")) << " &middot; code " << escape(s.value("code", ""))
       << " &middot; " << escape(s.value("method", "")) << " &middot; "
       << escape(s.value("frame_size", "")) << " &middot; "
       << std::lround(s.value("duration_s", 0.0)) << " s, stopped by "
       << escape(s.value("stopped_by", "")) << "</p>\n";
  html << "<div class=\"verdict " << verdict << "\" id=\"verdict\">Read rate "
       << figure_text(rate, true) << ": " << read << " of " << objects << " objects read, "
       << objects - read << " NO-READ" << (objects - read == 1 ? "" : "s") << ", " << dropped
       << " frame" << (dropped == 1 ? "" : "s") << " dropped</div>\n";
  auto card = [&](const std::string& value, const std::string& words) {
    html << "<div class=\"card\"><b>" << escape(value) << "</b>" << escape(words) << "</div>";
  };
  html << "<div class=\"cards\">";
  card(figure_text(rate, true), "read rate");
  card(std::to_string(objects - read), "NO-READs");
  card(figure_text(s.value("fps", 0.0), false), "frames per second");
  card(figure_text(s.value("latency_ms_p50", 0.0), false) + " / " +
           figure_text(s.value("latency_ms_p99", 0.0), false) + " ms",
       "latency, median / 99th percentile");
  card(std::to_string(dropped) + " / " + std::to_string(s.value("frames_captured", 0)),
       "frames dropped / captured");
  html << "</div>\n<h2>What went wrong, and what to do</h2>\n<ul class=\"findings\">\n";
  for (const Finding& f : findings) {
    std::string name = severity_name(f.severity);
    name[0] = static_cast<char>(std::toupper(name[0]));
    html << "<li class=\"" << severity_name(f.severity) << "\"><b>" << name << ":</b> "
         << escape(f.what);
    if (!f.to_do.empty()) html << "<br><span class=\"todo\">" << escape(f.to_do) << "</span>";
    html << "</li>\n";
  }
  html << "</ul>\n";

  std::vector<const ObjectResult*> listed, no_reads;
  for (const auto& o : in.objects) {
    listed.push_back(&o);
    if (!o.read()) no_reads.push_back(&o);
  }
  const auto omitted = s.value("object_results_omitted", std::uint64_t{0});
  if (!no_reads.empty()) {
    html << "<h2>NO-READs</h2>\n";
    folded_object_table(html, no_reads, "more NO-READs");
  }

  html << "<h2>Before and after</h2>\n";
  if (in.previews.empty()) html << "<p>No frames were kept.</p>\n";
  for (const auto& p : in.previews) {
    html << "<h3>" << escape(p.caption) << "</h3><div class=\"pair\"><div>"
         << image_tag(p.before, "captured frame " + std::to_string(p.sequence))
         << "<br>captured (coded blur)</div><div>"
         << image_tag(p.after, "fused frame " + std::to_string(p.sequence))
         << "<br>deblurred and fused</div></div>\n";
  }

  html << "<h2>Charts</h2>\n";
  for (const auto& c : charts)
    html << "<h3>" << escape(c.title) << "</h3>" << image_tag(read_bytes(c.file), c.title) << "\n";

  // Each object's read record (read_record.hpp), as the result lines carry it.
  html << "<h2>Objects</h2>\n";
  if (omitted > 0)
    html << "<p>The latest " << listed.size() << " objects; the " << omitted
         << " before them are in session.jsonl (its object_result lines).</p>\n";
  if (listed.empty()) html << "<p>No objects.</p>\n";
  folded_object_table(html, listed, "more objects");

  html << "<h2>All figures</h2><table>";
  for (const FigureName& f : kFigureNames)
    if (s.contains(f.key))
      html << "<tr><th style=\"text-align:left\">" << f.words << "</th><td>"
           << escape(figure_text(s[f.key], f.percent)) << "</td></tr>";
  html << "</table>\n";
  if (s.contains("rotation") && s["rotation"].value("frames_rotated", 0) > 0)
    html << "<p>Frame files rotated away to stay within the disk budget: "
         << s["rotation"]["frames_rotated"] << " frames.</p>\n";
  html << "<p>Every figure of the session is in summary.json, every frame and object in "
          "session.jsonl.</p>\n</body></html>\n";
  return html.str();
}

}  // namespace

std::string base64(const std::vector<std::uint8_t>& bytes) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::uint32_t a = bytes[i];
    const std::uint32_t b = i + 1 < bytes.size() ? bytes[i + 1] : 0;
    const std::uint32_t c = i + 2 < bytes.size() ? bytes[i + 2] : 0;
    const std::uint32_t triple = (a << 16) | (b << 8) | c;
    out += kAlphabet[(triple >> 18) & 63];
    out += kAlphabet[(triple >> 12) & 63];
    out += i + 1 < bytes.size() ? kAlphabet[(triple >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? kAlphabet[triple & 63] : '=';
  }
  return out;
}

std::string write_report(const std::string& folder, const ReportInputs& in) {
  const fs::path charts = fs::path(folder) / "charts";
  std::error_code ec;
  fs::create_directories(charts, ec);
  if (ec) return "cannot create '" + charts.string() + "': " + ec.message();

  std::vector<Chart> made;
  auto draw = [&](const plot::LineChart& chart, const std::string& name) -> std::string {
    const std::string path = (charts / name).string();
    if (auto problem = plot::write_png(chart, path, 900, 480); !problem.empty()) return problem;
    made.push_back({chart.title, path});
    return {};
  };

  if (in.latency_ms.count() > 0) {
    plot::LineChart chart;
    chart.title = "Latency: frame arrival to result";
    chart.x_label = "latency (ms)";
    chart.y_label = "frames";
    chart.y_min = 0;
    chart.series.push_back(histogram(in.latency_ms, 30, "", {0.1, 0.3, 0.7}));
    if (auto p = draw(chart, "latency.png"); !p.empty()) return p;
  }
  if (in.frames_per_second.count() > 0) {
    plot::LineChart chart;
    chart.title = "Throughput: frames processed in each second";
    chart.x_label = "frames per second";
    chart.y_label = "seconds";
    chart.y_min = 0;
    chart.series.push_back(histogram(in.frames_per_second, 20, "", {0.1, 0.55, 0.2}));
    if (auto p = draw(chart, "throughput.png"); !p.empty()) return p;
  }
  if (in.code.length() > 0) {
    plot::LineChart chart;
    chart.title = "The code's spectrum (continuous, linear blur)";
    chart.x_label = "frequency (cycles per slot)";
    chart.y_label = "dB (seed scale)";
    const plot::Rgb colours[3] = {{0.85, 0.1, 0.1}, {0.1, 0.6, 0.1}, {0.1, 0.2, 0.85}};
    const char* names[3] = {"LED 0 (red)", "LED 1 (green)", "LED 2 (blue)"};
    for (int led = 0; led < in.code.leds() && led < 3; ++led) {
      const auto sequence = codes::led_sequence(in.code, led);
      const auto spectrum = codes::dense_spectrum(sequence, 1024);
      plot::Series s;
      s.label = names[led];
      s.colour = colours[led];
      s.x = spectrum.frequency;
      s.y = spectrum.db;
      chart.series.push_back(std::move(s));
    }
    if (auto p = draw(chart, "spectrum.png"); !p.empty()) return p;
  }

  const std::string html = report_page(in, made);
  const fs::path target = fs::path(folder) / "report.html";
  const fs::path temporary = fs::path(folder) / ".report.html.tmp";
  {
    std::ofstream out(temporary, std::ios::binary);
    out << html;
    if (!out) return "cannot write '" + temporary.string() + "'";
  }
  fs::rename(temporary, target, ec);
  if (ec) return "cannot write '" + target.string() + "': " + ec.message();
  return {};
}

}  // namespace flutterscan::session
