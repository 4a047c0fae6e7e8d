// A tiny built-in bitmap font (5 x 7 pixels, printable ASCII, lower case drawn as upper case)
// for the viewer's status line: no font files or font libraries to find at run time.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace sphfem::render {

constexpr int kGlyphWidth = 5, kGlyphHeight = 7;

// Seven rows, top first; bit 4 of each row is the leftmost pixel. Characters outside
// printable ASCII show as '?'.
const std::uint8_t* glyph(char c);

// Coverage (0 or 255), rows top to bottom.
struct TextMask {
  int width = 0, height = 0;
  std::vector<std::uint8_t> alpha;
};

// `text` on one line, each font pixel `scale` x `scale` pixels, one font pixel between
// glyphs and around the text.
TextMask rasterize_text(const std::string& text, int scale);

}  // namespace sphfem::render
