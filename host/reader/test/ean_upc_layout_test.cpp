// The EAN/UPC layouts (ean_upc_layout.hpp) against the symbols ZXing's writer
// draws: their width in modules, their bars and spaces first bar to last, the
// guards' bars dark and spaces light, and each character's widths an L, G or R
// character of its digit.
#include "reader/ean_upc_layout.hpp"

#include <ZXing/BarcodeFormat.h>
#include <ZXing/BitMatrix.h>
#include <ZXing/MultiFormatWriter.h>
#include <gtest/gtest.h>

#include <array>
#include <string>
#include <vector>

namespace flutterscan::reader {
namespace {

struct Symbol {
  const char* format;
  ZXing::BarcodeFormat writer;
  const char* value;
};

TEST(EanUpcLayout, EachFormatsLayoutIsTheSymbolZxingDraws) {
  for (const Symbol& s : {Symbol{"EAN-13", ZXing::BarcodeFormat::EAN13, "5901234123457"},
                          Symbol{"UPC-A", ZXing::BarcodeFormat::UPCA, "036000291452"},
                          Symbol{"EAN-8", ZXing::BarcodeFormat::EAN8, "96385074"},
                          Symbol{"UPC-E", ZXing::BarcodeFormat::UPCE, "04252614"}}) {
    SCOPED_TRACE(s.format);
    ASSERT_TRUE(is_ean_upc(s.format));
    const auto layout = ean_upc_layout(s.format);
    ASSERT_TRUE(layout);
    const ZXing::BitMatrix m =
        ZXing::MultiFormatWriter(s.writer).setMargin(0).encode(s.value, 1, 1);
    ASSERT_EQ(m.width(), layout->modules);
    std::vector<int> bar(static_cast<std::size_t>(m.width()));
    for (int x = 0; x < m.width(); ++x) bar[static_cast<std::size_t>(x)] = m.get(x, 0) ? 1 : 0;
    std::size_t elements = 1;
    for (std::size_t x = 1; x < bar.size(); ++x) elements += bar[x] != bar[x - 1] ? 1 : 0;
    EXPECT_EQ(elements, layout->elements);
    EXPECT_EQ(layout->guard_bars.size() + layout->guard_spaces.size() +
                  kEanCharacterModules * layout->starts.size(),
              static_cast<std::size_t>(layout->modules));
    for (const int i : layout->guard_bars) EXPECT_EQ(bar[static_cast<std::size_t>(i)], 1) << i;
    for (const int i : layout->guard_spaces) EXPECT_EQ(bar[static_cast<std::size_t>(i)], 0) << i;
    // Each character: an L or G (left, space first) or R (right, bar first) of the widths.
    for (std::size_t c = 0; c < layout->starts.size(); ++c) {
      const bool left = static_cast<int>(c) < layout->left_characters;
      std::array<int, 4> w{};
      std::size_t run = 0;
      const auto first = static_cast<std::size_t>(layout->starts[c]);
      EXPECT_EQ(bar[first], left ? 0 : 1) << "character " << c;
      for (std::size_t x = first; x < first + kEanCharacterModules; ++x) {
        if (x > first && bar[x] != bar[x - 1]) ++run;
        ASSERT_LT(run, 4u) << "character " << c;
        ++w[run];
      }
      bool known = false;
      for (const auto& l : kEanLWidths)
        known = known || l == w ||
                (left && layout->both_parities && std::array<int, 4>{l[3], l[2], l[1], l[0]} == w);
      EXPECT_TRUE(known) << "character " << c;
    }
  }
  EXPECT_FALSE(is_ean_upc("Code128"));
  EXPECT_FALSE(ean_upc_layout("EAN13"));  // ZXing's reported names only
}

}  // namespace
}  // namespace flutterscan::reader
