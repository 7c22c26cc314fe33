#pragma once
// The second decoder (zbar, Debian's libzbar): linear codes read by the edges
// along each row rather than by thresholding it. ZXing binarizes a linear
// code's row at one level (the valley of the row's histogram); on print whose
// narrow spaces the optics leave grey between wide bars (a book's EAN-13 out
// of focus, 1.5-2 px modules), no level separates every bar, and ZXing reads
// nothing even on the sharp scene. zbar places each edge where the row's
// second difference changes sign and measures bar and space widths between
// edges, so a space that rises only part of the way to the paper still ends
// at its edges. barcode_reader.cpp tries it on a window ZXing read nothing in.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace flutterscan::reader {

/// \brief One symbol zbar read.
struct ZbarSymbol {
  std::string text;
  std::string format;        ///< ZXing's name: "EAN-13", "Code128", ...
  std::string symbology_id;  ///< ISO/IEC 15424: "]E0", "]C0", ...
  /// The scan lines' ends it was read between: the least and greatest x and y.
  int min_x = 0, min_y = 0, max_x = 0, max_y = 0;
  bool along_x = true;  ///< read along the rows (upright or upside down), else along columns
};

/// \brief zbar's names for the linear symbologies among `symbologies` (ZXing's
/// names, comma-separated) it reads: empty if none.
std::vector<std::string> zbar_symbologies(const std::string& symbologies);

/// \brief The linear symbols of `symbologies` (ZXing's names) zbar reads on
/// `lum` (8-bit luminance, `width` x `height`, rows packed), along rows and,
/// with `try_rotate`, along columns too. A symbol must decode alike on
/// kZbarAgreeingLines scan lines.
std::vector<ZbarSymbol> zbar_read(std::span<const std::uint8_t> lum, int width, int height,
                                  const std::string& symbologies, bool try_rotate);

/// \brief Scan lines a symbol must decode alike on (zbar's uncertainty + 1):
/// one noisy row of a deblurred latent can pass a check digit.
inline constexpr int kZbarAgreeingLines = 3;

}  // namespace flutterscan::reader
