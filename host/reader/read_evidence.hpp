#pragma once
// What backs a value (docs/algorithms.md, "Evidence for every value"). A
// symbology whose own check is strong (Code 128's mod-103 character, Code 93's
// two, the Reed-Solomon codes of QR, Data Matrix, Aztec and PDF417) vouches for
// its value. One whose check is weak does not: an EAN or UPC check digit
// catches one digit read wrong but lets one in ten two-digit errors through, and
// ITF, Code 39 and Codabar carry none that ZXing checks. Their values count
// only when a second, independent reading agrees: the symbol cut across its
// bars into two halves, each read on its own, gives the same value in both (the
// deblur works row by row, so the halves' noise is independent: a misread that
// noise makes would have to repeat on other noise), or the other decoder reads
// the same value in the window. Halves do not back a symbology with no check
// at all: its misreads are not only noise's but other print's (bars another
// symbol really has, an EAN add-on's, parse as a short one), which both halves
// hold alike; two decoders parse bars by different rules. Used by
// read_barcodes() only.

#include <ZXing/DecodeHints.h>

#include <cstdint>
#include <span>
#include <string>

#include "reader/barcode_reader.hpp"

namespace flutterscan::reader {

/// \brief Whether `format` (ZXing's name) has only a weak check (EAN-13, EAN-8,
/// UPC-A, UPC-E, ITF, Code 39, Codabar): its values need a second reading.
bool weak_check(const std::string& format);

/// \brief Whether `format` (ZXing's name) carries no check at all (ITF, Code
/// 39, Codabar: their optional check characters are not verified): its halves
/// do not back its values, only the other decoder does.
bool no_check(const std::string& format);

/// \brief The symbology family `format` belongs to: "EAN/UPC" for EAN-13,
/// EAN-8, UPC-A and UPC-E (one symbol's bars can decode as more than one of
/// them), else the format itself.
std::string symbology_family(const std::string& format);

/// \brief A window's luminance as a decoder saw it: `lum` packed rows of
/// `width` x `height`, its top left at (x0, y0) of the latent; `zbar_lum` the
/// same window in the view zbar reads (LuminanceView::kSrgbFromBlack).
struct LumWindow {
  std::span<const std::uint8_t> lum;
  int width = 0, height = 0;
  int x0 = 0, y0 = 0;
  std::span<const std::uint8_t> zbar_lum;
};

/// \brief What backs `code` (a value of a weak-check symbology read by
/// code.decoder in `window`), judged on the symbol's surroundings in the window
/// (its box widened by a quarter of its length along its reading direction and
/// half its length across: its quiet zones and bars, not the rest of a window
/// that may span a carton): "halves" where they, cut in two across the
/// symbol's bars at its centre, `independent_apart` - 1 rows left out at the
/// cut (DecodeWindow's: so that no sample of the frame is in both), reads the
/// same value in each half (by ZXing with `hints`, on the rows ZXing asks to
/// agree, two by default; or by zbar for a value zbar read): two readings with
/// independent noise on either side of the symbol's centre (not for no_check()
/// symbologies); "decoders" where the other decoder reads it there (zbar, in the view ZXing read it
/// in or in its own, for a value ZXing read); else empty: nothing does, and the value is not
/// reported. No halves where `independent_apart` is 0. `symbologies` and `try_rotate` as
/// read_barcodes() takes them.
std::string corroboration(const DecodedCode& code, const LumWindow& window,
                          const ZXing::DecodeHints& hints, const std::string& symbologies,
                          bool try_rotate, int independent_apart = 1);

}  // namespace flutterscan::reader
