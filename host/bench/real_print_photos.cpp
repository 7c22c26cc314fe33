#include "bench/real_print_photos.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <system_error>

#include "sim/photo_scene.hpp"

namespace flutterscan::bench {

namespace fs = std::filesystem;

std::vector<std::string> photo_files(const std::string& dir) {
  std::vector<std::string> files;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return files;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return std::tolower(c); });
    const bool image =
        ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".tif" || ext == ".tiff";
    if (image && entry.is_regular_file()) files.push_back(entry.path().string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

Result<std::vector<RealPhoto>, std::string> real_photos(const std::string& dir, int every,
                                                        const std::string& match) {
  using Out = Result<std::vector<RealPhoto>, std::string>;
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    return Out::failure("no photo folder at '" + dir +
                        "' (set FLUTTERSCAN_REAL_LABELS or give --photos)");
  std::vector<RealPhoto> photos;
  int seen = 0;
  for (const fs::path file : photo_files(dir)) {
    if (!fs::exists(fs::path(file).replace_extension(".txt"))) continue;
    const std::string name = file.stem().string();
    if (name.find(match) == std::string::npos) continue;
    if (seen++ % std::max(1, every) != 0) continue;
    std::ifstream in(fs::path(file).replace_extension(".txt"), std::ios::binary);
    photos.push_back(
        {name, file.string(),
         std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>())});
  }
  if (photos.empty()) return Out::failure("no photos with a .txt beside them in '" + dir + "'");
  return Out::success(std::move(photos));
}

imaging::Plane photo_file_grey(const std::string& path) {
  const cv::Mat grey = cv::imread(path, cv::IMREAD_GRAYSCALE);
  imaging::Plane plane(grey.cols, grey.rows);
  for (int y = 0; y < grey.rows; ++y)
    for (int x = 0; x < grey.cols; ++x) plane.at(x, y) = grey.at<std::uint8_t>(y, x) / 255.0f;
  return plane;
}

Result<sim::SceneSpec, std::string> photo_scene_spec(const std::string& path, double blur_px) {
  using Out = Result<sim::SceneSpec, std::string>;
  sim::SceneSpec spec;
  spec.kind = sim::SceneKind::kPhoto;
  spec.content = path;
  const auto size = sim::photo_frame_size(spec);
  if (!size.ok()) return Out::failure(size.error());
  spec.width = size.value().first + 2 * static_cast<int>(std::ceil(blur_px));
  spec.height = size.value().second;
  return Out::success(std::move(spec));
}

}  // namespace flutterscan::bench
