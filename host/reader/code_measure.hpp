#pragma once
// What a line engineer asks of a read beyond its value (docs/session-output.md,
// "The read record"): where the symbol lies, how big its modules are, and how
// well it is printed and imaged, measured on the fused latent (reflectance,
// white paper near 0.9) along the code.
//
// Linear codes (Code 128, EAN/UPC, Code 39/93, Codabar, ITF): ZXing gives the
// scan line it decoded on; the bars are found on the image from there (their
// ends along the code where the scan reflectance profile crosses its global
// threshold, their top and bottom where the profile across stops matching the
// centre's), and ten scans spread over 10%-90% of the bar height give the
// parameters ISO/IEC 15416 defines on a scan reflectance profile: Rmin, Rmax,
// symbol contrast SC = Rmax - Rmin, edge contrast ECmin (the least difference
// between adjacent elements' extremes), modulation ECmin / SC and defects
// (the largest element reflectance non-uniformity / SC). Each scan is graded
// by the standard's thresholds, the lowest parameter grade being the scan's,
// and the symbol's grade is the mean of the scans'.
//
// Matrix codes (QR, Data Matrix, Aztec, PDF417): the corners are ZXing's; the
// modules per side come from the period of the edges inside the symbol; the
// reflectance at each module's centre gives SC and the modulation (ISO/IEC
// 15415's, without the error-correction budget), and the sides give the axial
// non-uniformity.
//
// The grade is INDICATIVE, never a verification: the latent is not an ISO
// measuring aperture, its reflectance is not calibrated against a reference
// standard, lighting and optics are not the standard's, decodability is not
// computed (ZXing's decode stands in for the reference decode), and quiet zones
// are not checked.

#include <array>
#include <string>

#include "imaging/image.hpp"

namespace flutterscan::reader {

/// \brief A point of the latent image, pixels (x right, y down).
struct CodePoint {
  double x = 0;
  double y = 0;
};

/// \brief A symbol's corners: top-left, top-right, bottom-right, bottom-left,
/// in the symbol's own frame (its reading direction left to right).
using CodeCorners = std::array<CodePoint, 4>;

/// \brief What measure_code() found (all reflectances in latent units, 0..1).
struct CodeQuality {
  bool measured = false;        ///< false: the symbol could not be measured (see `problem`)
  std::string problem;          ///< why not, when not measured
  CodeCorners corners{};        ///< refined on the image for linear codes
  double module_px = 0;         ///< the narrowest element (linear) or one module (matrix)
  int modules = 0;              ///< modules along the code (linear) or per side (matrix)
  double r_min = 0, r_max = 0;  ///< mean over the scans (linear), over the module centres (matrix)
  double symbol_contrast = 0;   ///< SC = Rmax - Rmin
  double edge_contrast = 0;     ///< linear: ECmin, mean over the scans; matrix: 0
  double modulation = 0;        ///< linear: ECmin / SC; matrix: 5th percentile of the modules'
  double defects = 0;           ///< linear: ERNmax / SC; matrix: 0
  double axial_nonuniformity = 0;  ///< matrix: |width - height| / mean side; linear: 0
  int scans = 0;                   ///< scan lines measured (linear), 1 for matrix codes
  double grade_value = 0;          ///< 4 = A ... 0 = F, mean over the scans
  char grade = 'F';                ///< indicative, not a verification
};

/// \brief True for ZXing's linear formats ("Code128", "EAN-13", ...).
bool is_linear_format(const std::string& format);

/// \brief The letter of an ISO-style grade value (A >= 3.5, B >= 2.5, C >= 1.5, D >= 0.5, else F).
char grade_letter(double value);

/// \brief Measures the symbol of ZXing format `format` that ZXing found at
/// `corners` on `latent`. Never throws; a symbol it cannot measure comes back
/// with measured = false, a reason, and ZXing's corners.
CodeQuality measure_code(const imaging::Plane& latent, const std::string& format,
                         const CodeCorners& corners);

}  // namespace flutterscan::reader
