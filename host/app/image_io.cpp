#include "app/image_io.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <sstream>
#include <vector>

#include "imaging/limits.hpp"

namespace flutterscan::app {
namespace {

namespace fs = std::filesystem;

/// A temporary name beside `path` keeping its extension (OpenCV picks the format by it).
std::string temporary_beside(const std::string& path) {
  const fs::path target(path);
  std::random_device device;
  std::string name = ".";  // appended piecewise: GCC 12 warns falsely on "." + std::string
  name += target.stem().string();
  name += ".tmp";
  name += std::to_string(device());
  name += target.extension().string();
  return (target.parent_path() / name).string();
}

std::string folder_problem(const std::string& path) {
  const fs::path parent = fs::path(path).parent_path();
  if (!parent.empty() && !fs::is_directory(parent))
    return "cannot write '" + path + "': folder '" + parent.string() + "' does not exist";
  return {};
}

std::string commit(const std::string& temporary, const std::string& path) {
  std::error_code error;
  fs::rename(temporary, path, error);
  if (error) {
    fs::remove(temporary, error);
    return "cannot write '" + path + "': " + error.message();
  }
  return {};
}

}  // namespace

Result<std::pair<std::uint32_t, std::uint32_t>, std::string> declared_frame_size(
    std::span<const std::uint8_t> b) {
  using Out = Result<std::pair<std::uint32_t, std::uint32_t>, std::string>;
  static constexpr std::uint8_t kPng[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (b.size() >= 8 && std::equal(std::begin(kPng), std::end(kPng), b.begin())) {
    // The first chunk is IHDR: width and height, big-endian, at bytes 16 and 20.
    if (b.size() < 24 || std::string(b.begin() + 12, b.begin() + 16) != "IHDR")
      return Out::failure("a PNG without its IHDR header");
    auto be32 = [&](std::size_t at) {
      return std::uint32_t{b[at]} << 24 | std::uint32_t{b[at + 1]} << 16 |
             std::uint32_t{b[at + 2]} << 8 | b[at + 3];
    };
    return Out::success({be32(16), be32(20)});
  }
  const bool little = b.size() >= 4 && b[0] == 'I' && b[1] == 'I' && b[2] == 42 && b[3] == 0;
  const bool big = b.size() >= 4 && b[0] == 'M' && b[1] == 'M' && b[2] == 0 && b[3] == 42;
  if (!little && !big) return Out::failure("not a PNG or TIFF image");
  auto read = [&](std::size_t at, int bytes) -> std::uint64_t {
    std::uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) {
      const std::uint64_t byte = b[at + static_cast<std::size_t>(i)];
      v |= little ? byte << (8 * i) : byte << (8 * (bytes - 1 - i));
    }
    return v;
  };
  if (b.size() < 8) return Out::failure("a TIFF without its header");
  const std::uint64_t ifd = read(4, 4);
  if (ifd + 2 > b.size()) return Out::failure("a TIFF whose first directory is past its end");
  const std::uint64_t entries = read(ifd, 2);
  std::uint64_t width = 0, height = 0;
  for (std::uint64_t e = 0; e < entries; ++e) {
    const std::uint64_t at = ifd + 2 + 12 * e;
    if (at + 12 > b.size()) return Out::failure("a TIFF directory past the file's end");
    const auto tag = read(at, 2), type = read(at + 2, 2);
    const std::uint64_t value = type == 3 ? read(at + 8, 2) : read(at + 8, 4);  // SHORT or LONG
    if (tag == 256) width = value;
    if (tag == 257) height = value;
  }
  if (width == 0 || height == 0) return Out::failure("a TIFF without ImageWidth and ImageLength");
  return Out::success({static_cast<std::uint32_t>(width), static_cast<std::uint32_t>(height)});
}

Result<LoadedFrame, std::string> read_frame(const std::string& path) {
  using Out = Result<LoadedFrame, std::string>;
  if (!fs::exists(path)) return Out::failure("'" + path + "' does not exist");
  std::ifstream in(path, std::ios::binary);
  if (!in) return Out::failure("cannot read '" + path + "'");
  const std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(in),
                                        std::istreambuf_iterator<char>()};
  return decode_frame(bytes, path);
}

Result<LoadedFrame, std::string> decode_frame(std::span<const std::uint8_t> bytes,
                                              const std::string& path) {
  using Out = Result<LoadedFrame, std::string>;
  const auto size = declared_frame_size(bytes);
  if (!size.ok()) return Out::failure("cannot read '" + path + "': " + size.error());
  const auto [width, height] = size.value();
  if (width < 1 || height < 1 || width > imaging::kMaxFrameSidePx ||
      height > imaging::kMaxFrameSidePx ||
      std::uint64_t{width} * height > static_cast<std::uint64_t>(imaging::kMaxFramePixels))
    return Out::failure("'" + path + "' declares " + std::to_string(width) + " x " +
                        std::to_string(height) + " px: frames are 1.." +
                        std::to_string(imaging::kMaxFrameSidePx) + " px a side and at most " +
                        std::to_string(imaging::kMaxFramePixels) + " pixels");
  if (bytes.size() > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    return Out::failure("'" + path + "' is larger than 2 GB");
  cv::Mat mat;
  try {
    const cv::Mat encoded(1, static_cast<int>(bytes.size()), CV_8U,
                          const_cast<std::uint8_t*>(bytes.data()));
    mat = cv::imdecode(encoded, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    return Out::failure("cannot read '" + path + "': " + e.what());
  }
  if (mat.empty())
    return Out::failure("cannot read '" + path + "': not a PNG or TIFF image OpenCV can decode");
  if (mat.dims != 2 || mat.cols != static_cast<int>(width) || mat.rows != static_cast<int>(height))
    return Out::failure("'" + path + "' decodes to another size than its header declares");
  if (mat.depth() != CV_8U && mat.depth() != CV_16U)
    return Out::failure("'" + path + "' is not an 8- or 16-bit image");
  if (mat.channels() == 4) {
    // An alpha channel that hides nothing (every pixel opaque) is dropped:
    // some tools write one whatever the picture; one that hides pixels is refused.
    cv::Mat alpha;
    cv::extractChannel(mat, alpha, 3);
    const double opaque = mat.depth() == CV_8U ? 255 : 65535;
    cv::Point where;
    double least = 0;
    cv::minMaxLoc(alpha, &least, nullptr, &where);
    if (least < opaque)
      return Out::failure("'" + path + "' has transparent pixels (alpha " +
                          std::to_string(static_cast<int>(least)) + " at x " +
                          std::to_string(where.x) + ", y " + std::to_string(where.y) +
                          "): give RGB or grey");
    cv::cvtColor(mat, mat, cv::COLOR_BGRA2BGR);
  }
  if (mat.channels() != 1 && mat.channels() != 3)
    return Out::failure("'" + path + "' has " + std::to_string(mat.channels()) +
                        " channels: give RGB or grey");
  LoadedFrame frame;
  frame.container_bits = mat.depth() == CV_8U ? 8 : 16;
  cv::Mat as_float;
  mat.convertTo(as_float, CV_32F);
  std::vector<cv::Mat> planes;
  cv::split(as_float, planes);
  if (planes.size() == 3) std::swap(planes[0], planes[2]);  // OpenCV stores BGR
  for (const cv::Mat& p : planes) {
    imaging::Plane plane(p.cols, p.rows);
    for (int y = 0; y < p.rows; ++y)
      std::copy(p.ptr<float>(y), p.ptr<float>(y) + p.cols, plane.row(y).begin());
    frame.dn.channels.push_back(std::move(plane));
  }
  return Out::success(std::move(frame));
}

std::string write_png16(const std::string& path, const imaging::Image& image) {
  if (auto problem = folder_problem(path); !problem.empty()) return problem;
  std::vector<cv::Mat> planes;
  for (const auto& plane : image.channels) {
    cv::Mat m(plane.height, plane.width, CV_16U);
    for (int y = 0; y < plane.height; ++y) {
      auto* dst = m.ptr<std::uint16_t>(y);
      const auto src = plane.row(y);
      for (int x = 0; x < plane.width; ++x)
        dst[x] = static_cast<std::uint16_t>(
            std::clamp(std::lround(src[static_cast<std::size_t>(x)]), 0L, 65535L));
    }
    planes.push_back(m);
  }
  if (planes.size() == 3) std::swap(planes[0], planes[2]);
  cv::Mat merged;
  cv::merge(planes, merged);
  const std::string temporary = temporary_beside(path);
  bool written = false;
  try {
    written = cv::imwrite(temporary, merged);
  } catch (const cv::Exception& e) {
    written = false;
  }
  if (!written) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    return "cannot write '" + path + "': OpenCV could not encode it (use a .png name)";
  }
  return commit(temporary, path);
}

Result<nlohmann::json, std::string> read_json(const std::string& path) {
  using Out = Result<nlohmann::json, std::string>;
  std::ifstream in(path);
  if (!in) return Out::failure("cannot read '" + path + "'");
  try {
    return Out::success(nlohmann::json::parse(in));
  } catch (const nlohmann::json::parse_error& e) {
    return Out::failure("'" + path + "' is not valid JSON: " + e.what());
  }
}

std::string write_text(const std::string& path, const std::string& text) {
  if (auto problem = folder_problem(path); !problem.empty()) return problem;
  const std::string temporary = temporary_beside(path);
  {
    std::ofstream out(temporary, std::ios::binary);
    out << text;
    if (!out.flush()) {
      std::error_code ignored;
      fs::remove(temporary, ignored);
      return "cannot write '" + path + "'";
    }
  }
  return commit(temporary, path);
}

std::string sibling_path(const std::string& path, const std::string& suffix,
                         const std::string& extension) {
  fs::path p(path);
  return (p.parent_path() / (p.stem().string() + suffix + extension)).string();
}

}  // namespace flutterscan::app
