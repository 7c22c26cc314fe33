#include "reader/zbar_reader.hpp"

#include <ZXing/BarcodeFormat.h>
#include <zbar.h>

#include <algorithm>
#include <array>
#include <memory>
#include <stdexcept>

namespace flutterscan::reader {

// zbar.h declares its C interface in namespace zbar when compiled as C++.
using namespace zbar;

namespace {

/// A linear symbology both decoders read: ZXing's name, zbar's type and
/// name, and the ISO/IEC 15424 identifier of its plain form.
struct Linear {
  const char* zxing;
  zbar_symbol_type_t zbar;
  const char* zbar_name;
  const char* identifier;
};

constexpr std::array<Linear, 11> kLinear = {{
    {"Codabar", ZBAR_CODABAR, "Codabar", "]F0"},
    {"Code39", ZBAR_CODE39, "Code 39", "]A0"},
    {"Code93", ZBAR_CODE93, "Code 93", "]G0"},
    {"Code128", ZBAR_CODE128, "Code 128", "]C0"},
    {"EAN-8", ZBAR_EAN8, "EAN-8", "]E4"},
    {"EAN-13", ZBAR_EAN13, "EAN-13", "]E0"},
    {"ITF", ZBAR_I25, "Interleaved 2 of 5", "]I0"},
    {"UPC-A", ZBAR_UPCA, "UPC-A", "]E0"},
    {"UPC-E", ZBAR_UPCE, "UPC-E", "]E0"},
    {"DataBar", ZBAR_DATABAR, "DataBar", "]e0"},
    {"DataBarExpanded", ZBAR_DATABAR_EXP, "DataBar Expanded", "]e0"},
}};

/// The entries of kLinear `symbologies` names (ZXing's names, as ZXing parses them).
std::vector<const Linear*> named(const std::string& symbologies) {
  std::vector<const Linear*> out;
  ZXing::BarcodeFormats formats;
  try {
    formats = ZXing::BarcodeFormatsFromString(symbologies);
  } catch (const std::exception&) {
    return out;  // not a list ZXing knows (check_symbologies() says so before)
  }
  for (const Linear& l : kLinear)
    if (formats.testFlag(ZXing::BarcodeFormatFromString(l.zxing))) out.push_back(&l);
  return out;
}

struct ScannerDeleter {
  void operator()(zbar_image_scanner_t* s) const { zbar_image_scanner_destroy(s); }
};
struct ImageDeleter {
  void operator()(zbar_image_t* i) const { zbar_image_destroy(i); }
};

}  // namespace

std::vector<std::string> zbar_symbologies(const std::string& symbologies) {
  std::vector<std::string> out;
  for (const Linear* l : named(symbologies)) out.emplace_back(l->zbar_name);
  return out;
}

std::vector<ZbarSymbol> zbar_read(std::span<const std::uint8_t> lum, int width, int height,
                                  const std::string& symbologies, bool try_rotate) {
  std::vector<ZbarSymbol> out;
  const std::vector<const Linear*> linear = named(symbologies);
  if (linear.empty() || width < 1 || height < 1 ||
      lum.size() < static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
    return out;
  const std::unique_ptr<zbar_image_scanner_t, ScannerDeleter> scanner(zbar_image_scanner_create());
  zbar_image_scanner_set_config(scanner.get(), ZBAR_NONE, ZBAR_CFG_ENABLE, 0);
  for (const Linear* l : linear)
    zbar_image_scanner_set_config(scanner.get(), l->zbar, ZBAR_CFG_ENABLE, 1);
  // Every row (zbar's "y density": rows apart); every column (its "x
  // density") only where codes turned by 90 degrees are looked for.
  zbar_image_scanner_set_config(scanner.get(), ZBAR_NONE, ZBAR_CFG_Y_DENSITY, 1);
  zbar_image_scanner_set_config(scanner.get(), ZBAR_NONE, ZBAR_CFG_X_DENSITY, try_rotate ? 1 : 0);
  const std::unique_ptr<zbar_image_t, ImageDeleter> image(zbar_image_create());
  zbar_image_set_format(image.get(), zbar_fourcc('Y', '8', '0', '0'));
  zbar_image_set_size(image.get(), static_cast<unsigned>(width), static_cast<unsigned>(height));
  // zbar reads the samples in place and frees nothing (no cleanup handler).
  zbar_image_set_data(image.get(), lum.data(),
                      static_cast<unsigned long>(width) * static_cast<unsigned long>(height),
                      nullptr);
  if (zbar_scan_image(scanner.get(), image.get()) <= 0) return out;
  for (const zbar_symbol_t* s = zbar_image_first_symbol(image.get()); s != nullptr;
       s = zbar_symbol_next(s)) {
    if (zbar_symbol_get_quality(s) < kZbarAgreeingLines) continue;
    const auto type = zbar_symbol_get_type(s);
    const auto known = std::find_if(kLinear.begin(), kLinear.end(),
                                    [&](const Linear& l) { return l.zbar == type; });
    const unsigned points = zbar_symbol_get_loc_size(s);
    if (known == kLinear.end() || points == 0) continue;
    ZbarSymbol symbol;
    symbol.text.assign(zbar_symbol_get_data(s), zbar_symbol_get_data_length(s));
    symbol.format = known->zxing;
    symbol.symbology_id = known->identifier;
    symbol.min_x = symbol.max_x = zbar_symbol_get_loc_x(s, 0);
    symbol.min_y = symbol.max_y = zbar_symbol_get_loc_y(s, 0);
    for (unsigned i = 1; i < points; ++i) {
      symbol.min_x = std::min(symbol.min_x, zbar_symbol_get_loc_x(s, i));
      symbol.max_x = std::max(symbol.max_x, zbar_symbol_get_loc_x(s, i));
      symbol.min_y = std::min(symbol.min_y, zbar_symbol_get_loc_y(s, i));
      symbol.max_y = std::max(symbol.max_y, zbar_symbol_get_loc_y(s, i));
    }
    const zbar_orientation_t turn = zbar_symbol_get_orientation(s);
    symbol.along_x = turn != ZBAR_ORIENT_RIGHT && turn != ZBAR_ORIENT_LEFT;
    out.push_back(std::move(symbol));
  }
  return out;
}

}  // namespace flutterscan::reader
