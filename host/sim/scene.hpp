#pragma once
// Scenes for the simulator: the latent reflectance image of what passes under
// the camera (docs/conventions.md: white = 1, black print about 0.05).
//
// A barcode or text scene is a white label (paper reflectance) centred on a
// belt of another grey; the print on it has the ink reflectance. Barcodes come
// from ZXing-C++'s encoders and are drawn with exact module edges: each pixel
// is the area average of the module grid over its square, so a fractional
// module size (2.5 px) gives honest grey edge pixels rather than bars rounded
// to whole pixels. Quiet zones are part of the label: 10 modules either side
// of a Code 128, 11 of an EAN-13 (and 5 above and below the bars), 4 around a
// QR code, 2 around a Data Matrix. Linear bars are between 15% and 30% of the
// symbol's width high: the full 30% when the image has room, less when it is
// short. Text is FONT_HERSHEY_SIMPLEX with a cap height of 7 modules and a
// stroke of 0.8 modules, with 4 modules of paper around it. Every label keeps
// at least kMinBeltPx of belt on each side; a label that cannot is an error
// naming the image size it needs.
//
// An image scene is a picture file taken as reflectance: 8- and 16-bit files
// are sRGB-encoded (linearised, then Rec. 709 luminance), float files linear;
// it fills the whole frame (resized to width x height), with no label or belt.
//
// A photo scene is a photograph of a real label placed on the belt, one
// reflectance per LED band (sim/photo_scene.hpp); render_scene() gives its
// grey view, the bands' fusion (sim::fuse_bands).

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "flutterscan/common/result.hpp"
#include "imaging/image.hpp"

namespace flutterscan::sim {

/// \brief What a scene shows.
enum class SceneKind {
  kCode128,
  kEan13,
  kQr,
  kDataMatrix,
  kText,
  kImage,
  kFlat,   ///< one reflectance over the whole frame: a calibration target
  kPhoto,  ///< a photo of a real label on the belt (sim/photo_scene.hpp)
};

/// \brief Belt visible on each side of a label, pixels (at least).
inline constexpr int kMinBeltPx = 8;

/// \brief A scene to render.
struct SceneSpec {
  SceneKind kind = SceneKind::kCode128;
  std::string content;  ///< barcode text, printed text, or image path
  int width = 640;      ///< output size, pixels
  int height = 360;
  double module_px = 3;  ///< barcode module (narrowest bar) in px; text: cap height = 7 modules
  double paper = 0.9;    ///< reflectance of the label
  double ink = 0.06;     ///< reflectance of the print
  double belt = 0.35;    ///< reflectance of the belt around the label
  /// Real print is not pixel-exact: ink spreads (a Gaussian of this sigma, px, over the
  /// label's edges) and paper and toner vary (each pixel's reflectance times 1 + texture x a
  /// standard normal, clipped to 0..1). 0 and 0 give exact two-tone labels. Image scenes
  /// ignore both.
  double print_blur_px = 0;
  double texture = 0;
  std::uint64_t texture_seed = 1;
  /// Photo scenes: the photo turned about its centre, degrees, anticlockwise on the image.
  double rotate_deg = 0;
};

/// \brief The name parse_scene() knows a kind by ("code128", "ean13", "qr",
/// "datamatrix", "text", "image", "flat", "photo").
std::string_view scene_kind_name(SceneKind kind);

/// \brief The EAN-13 check digit of the first 12 of `digits` (decimal digits, at
/// least 12): weights 1, 3, 1, 3, ... from the left.
int ean13_check_digit(std::string_view digits);

/// \brief Parses "KIND:CONTENT" (code128:TEXT, ean13:DIGITS, qr:TEXT,
/// datamatrix:TEXT, text:WORDS, image:PATH, flat:REFLECTANCE, photo:PATH) into a spec with
/// default size and
/// reflectances. Content is everything after the first colon. An EAN-13 takes
/// 12 digits (the check digit is added) or 13 with a correct check digit;
/// Code 128 and text take printable ASCII. The error names the problem.
Result<SceneSpec, std::string> parse_scene(const std::string& text);

/// \brief Renders the reflectance image of `spec` (values in [0, 1]),
/// `supersample` (1 to 16) times finer than its size in both directions, for
/// sim::expected_electrons(); sim::bin_pixels() gives the camera's sharp view.
/// Errors: bad sizes or reflectances, content the barcode format rejects, a
/// label that does not fit (the message gives the image size needed), an image
/// file that cannot be read.
Result<imaging::Plane, std::string> render_scene(const SceneSpec& spec, int supersample = 1);

/// \brief Where a barcode scene's symbol lies in the image render_scene()
/// makes at supersample 1: what a reader should find there.
struct SymbolPlacement {
  /// Top-left, top-right, bottom-right, bottom-left of the symbol (its outer
  /// module edges; for linear codes, first bar to last and the bars' height),
  /// in pixel-centre coordinates: pixel (x, y)'s centre is (x, y).
  std::array<std::array<double, 2>, 4> corners{};
  double module_px = 0;
  int modules = 0;           ///< along the code (linear) or per row (matrix)
  std::string symbology_id;  ///< ISO/IEC 15424: "]C0", "]E0", "]Q1", "]d1"
};

/// \brief The symbol's placement in a barcode scene (code128, ean13, qr,
/// datamatrix); other kinds and specs render_scene() refuses are errors.
Result<SymbolPlacement, std::string> symbol_placement(const SceneSpec& spec);

}  // namespace flutterscan::sim
