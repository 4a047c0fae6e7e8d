// The viewer's bitmap font: glyph shapes and the size of a rasterised line.
#include <gtest/gtest.h>

#include <string>

#include "sphfem/render/font.h"

namespace sphfem::render {
namespace {

TEST(RenderFont, GlyphsHaveTheirShapes) {
  // 'T': a full top row, then the middle column.
  const std::uint8_t* t = glyph('T');
  EXPECT_EQ(t[0], 0x1f);
  for (int r = 1; r < kGlyphHeight; ++r) EXPECT_EQ(t[r], 0x04) << r;
  // A space is empty; lower case is drawn as upper case; unknown characters as '?'.
  for (int r = 0; r < kGlyphHeight; ++r) EXPECT_EQ(glyph(' ')[r], 0);
  auto rows = [](char c) {
    return std::string(reinterpret_cast<const char*>(glyph(c)), kGlyphHeight);
  };
  EXPECT_EQ(rows('a'), rows('A'));
  EXPECT_EQ(rows('\x01'), rows('?'));
  // Every digit differs from every other.
  for (char a = '0'; a <= '9'; ++a)
    for (char b = char(a + 1); b <= '9'; ++b) EXPECT_NE(rows(a), rows(b));
}

TEST(RenderFont, RasterisedLineHasItsSizeAndPixels) {
  const TextMask m = rasterize_text("T1", 2);
  EXPECT_EQ(m.width, (2 * (kGlyphWidth + 1) + 1) * 2);
  EXPECT_EQ(m.height, (kGlyphHeight + 2) * 2);
  ASSERT_EQ(m.alpha.size(), std::size_t(m.width) * m.height);
  auto at = [&](int x, int y) { return m.alpha[std::size_t(y) * m.width + x]; };
  // The border stays clear; the T's top-left pixel (font pixel 1, 1) is set, scaled by 2.
  EXPECT_EQ(at(0, 0), 0);
  EXPECT_EQ(at(2, 2), 255);
  EXPECT_EQ(at(3, 3), 255);
  // Below the T's bar, left of its stem: clear.
  EXPECT_EQ(at(2, 4), 0);
}

}  // namespace
}  // namespace sphfem::render
