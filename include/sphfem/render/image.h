// An 8-bit RGB picture and a PNG writer for it (zlib does the deflate).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace sphfem::render {

// Rows top to bottom, 3 bytes (r, g, b) per pixel.
struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;

  Image() = default;
  Image(int w, int h) : width(w), height(h), rgb(std::size_t(w) * std::size_t(h) * 3, 0) {}
  std::uint8_t* at(int x, int y) { return rgb.data() + (std::size_t(y) * width + x) * 3; }
  const std::uint8_t* at(int x, int y) const {
    return rgb.data() + (std::size_t(y) * width + x) * 3;
  }
};

// The PNG file contents: 8-bit truecolour, no interlace, every scanline with the Up filter,
// deflated by zlib.
std::string encode_png(const Image& image);

// Writes encode_png(image) atomically (see io/atomic_file.h); throws std::runtime_error
// naming the path on failure and std::invalid_argument for an empty image.
void write_png(const std::string& path, const Image& image);

}  // namespace sphfem::render
