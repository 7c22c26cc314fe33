#include "app/image_io.hpp"

#include <opencv2/imgcodecs.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

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

Result<LoadedFrame, std::string> read_frame(const std::string& path) {
  using Out = Result<LoadedFrame, std::string>;
  if (!fs::exists(path)) return Out::failure("'" + path + "' does not exist");
  cv::Mat mat;
  try {
    mat = cv::imread(path, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    return Out::failure("cannot read '" + path + "': " + e.what());
  }
  if (mat.empty())
    return Out::failure("cannot read '" + path + "': not a PNG or TIFF image OpenCV can decode");
  if (mat.depth() != CV_8U && mat.depth() != CV_16U)
    return Out::failure("'" + path + "' is not an 8- or 16-bit image");
  if (mat.channels() == 4)
    return Out::failure("'" + path + "' has an alpha channel: give RGB or grey");
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
