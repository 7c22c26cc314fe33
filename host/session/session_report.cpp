#include "session/session_report.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "codes/spectrum.hpp"
#include "plot/line_chart.hpp"
#include "session/read_record.hpp"

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

  struct Chart {
    std::string title;
    std::string file;
  };
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

  std::ostringstream html;
  const auto& s = in.summary;
  html << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
       << "<title>flutterscan session report</title><style>"
       << "body{font-family:sans-serif;margin:2em;max-width:1200px}"
       << "table{border-collapse:collapse}td,th{border:1px solid #bbb;padding:2px "
          "8px;text-align:right}"
       << "th{background:#eee}.noread{background:#fdd}img{max-width:100%;border:1px solid #ccc}"
       << ".pair{display:grid;grid-template-columns:1fr 1fr;gap:8px;margin-bottom:1em}"
       << "</style></head><body>\n<h1>flutterscan session report</h1>\n";
  html << "<h2>Summary</h2><table>";
  auto row = [&](const std::string& name, const nlohmann::json& value) {
    html << "<tr><th style=\"text-align:left\">" << escape(name) << "</th><td>"
         << escape(value.is_string() ? value.get<std::string>() : value.dump()) << "</td></tr>";
  };
  for (const char* key :
       {"camera", "controller", "code", "method", "frames_captured", "frames_processed",
        "frames_dropped", "frames_without_event", "events_without_frame", "camera_frames_lost",
        "objects", "objects_read", "object_read_rate", "fps", "latency_ms_p50", "latency_ms_p99",
        "clock_drift_ppm", "stopped_by", "duration_s"})
    if (s.contains(key)) row(key, s[key]);
  html << "</table>\n";
  if (s.contains("rotation") && s["rotation"].value("frames_rotated", 0) > 0)
    html << "<p>Frame files rotated away to stay within the disk budget: "
         << s["rotation"]["frames_rotated"] << " frames (see summary.json).</p>\n";

  html << "<h2>Before and after</h2>\n";
  if (in.previews.empty()) html << "<p>No frames were kept.</p>\n";
  for (const auto& p : in.previews) {
    html << "<h3>" << escape(p.caption) << "</h3><div class=\"pair\"><div>"
         << image_tag(p.before_png, "captured frame " + std::to_string(p.sequence))
         << "<br>captured (coded blur)</div><div>"
         << image_tag(p.after_png, "fused frame " + std::to_string(p.sequence))
         << "<br>deblurred and fused</div></div>\n";
  }

  // The table shows each object's read record (read_record.hpp), as the result lines carry it.
  html << "<h2>Decodes per object</h2><table><tr><th>object</th><th>belt px</th><th>frames</th>"
       << "<th>decoded</th><th>rate</th><th>status</th><th>format</th><th>identifier</th>"
       << "<th>value</th><th>module px</th><th>grade (indicative)</th><th>time (UTC)</th>"
       << "<th>kept frame</th></tr>\n";
  for (const auto& o : in.objects) {
    const nlohmann::json r = read_record(o);
    html << "<tr" << (o.read() ? "" : " class=\"noread\"") << "><td>" << o.id << "</td><td>"
         << std::lround(o.belt_px) << "</td><td>" << o.frames_seen << "</td><td>"
         << o.frames_decoded << "</td><td>" << std::lround(100 * o.decode_rate()) << "%</td><td>"
         << (o.read() ? "READ" : "NO-READ") << "</td><td>" << escape(o.format) << "</td><td>"
         << escape(r.value("symbology_id", "")) << "</td><td style=\"text-align:left\">"
         << escape(o.value) << "</td><td>"
         << (r.contains("module_px") ? escape(r["module_px"].dump()) : "") << "</td><td>"
         << (r.contains("quality") && r["quality"].contains("grade")
                 ? escape(r["quality"]["grade"].get<std::string>())
                 : "")
         << "</td><td>" << escape(r.value("time", "")) << "</td><td>"
         << escape(r.value("frame_file", "")) << "</td></tr>\n";
  }
  html << "</table>\n<h2>Charts</h2>\n";
  for (const auto& c : made)
    html << "<h3>" << escape(c.title) << "</h3>" << image_tag(read_bytes(c.file), c.title) << "\n";
  html << "</body></html>\n";

  const fs::path target = fs::path(folder) / "report.html";
  const fs::path temporary = fs::path(folder) / ".report.html.tmp";
  {
    std::ofstream out(temporary, std::ios::binary);
    out << html.str();
    if (!out) return "cannot write '" + temporary.string() + "'";
  }
  fs::rename(temporary, target, ec);
  if (ec) return "cannot write '" + target.string() + "': " + ec.message();
  return {};
}

}  // namespace flutterscan::session
