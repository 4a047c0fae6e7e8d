// PNG writer: the file read back chunk by chunk (CRCs, IHDR), inflated by zlib and
// unfiltered down to the original pixels.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <zlib.h>

#include "sphfem/render/image.h"

namespace sphfem::render {
namespace {

std::uint32_t be32(const std::string& s, std::size_t at) {
  return std::uint32_t(std::uint8_t(s[at])) << 24 | std::uint32_t(std::uint8_t(s[at + 1])) << 16 |
         std::uint32_t(std::uint8_t(s[at + 2])) << 8 | std::uint32_t(std::uint8_t(s[at + 3]));
}

struct Decoded {
  std::uint32_t width = 0, height = 0;
  std::string ihdr_tail;  // depth, colour type, compression, filter, interlace
  std::string raw;        // inflated IDAT
};

// Reads back what encode_png writes; any structural fault fails the test.
Decoded decode(const std::string& png) {
  Decoded d;
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  std::string idat;
  std::size_t at = 8;
  std::string last;
  while (at + 12 <= png.size()) {
    const std::uint32_t len = be32(png, at);
    const std::string type = png.substr(at + 4, 4);
    const std::string data = png.substr(at + 8, len);
    EXPECT_EQ(be32(png, at + 8 + len),
              std::uint32_t(crc32(0, reinterpret_cast<const Bytef*>(png.data() + at + 4), len + 4)))
        << type;
    if (type == "IHDR") {
      EXPECT_EQ(len, 13u);
      d.width = be32(data, 0);
      d.height = be32(data, 4);
      d.ihdr_tail = data.substr(8);
    } else if (type == "IDAT") {
      idat += data;
    }
    last = type;
    at += 12 + len;
  }
  EXPECT_EQ(at, png.size());
  EXPECT_EQ(last, "IEND");

  // Inflate with zlib (which checks the Adler-32), then undo each row's filter.
  EXPECT_EQ((std::uint8_t(idat[0]) * 256 + std::uint8_t(idat[1])) % 31, 0);
  const std::size_t row = std::size_t(d.width) * 3;
  std::string filtered((row + 1) * d.height, '\0');
  uLongf n = uLongf(filtered.size());
  EXPECT_EQ(uncompress(reinterpret_cast<Bytef*>(filtered.data()), &n,
                       reinterpret_cast<const Bytef*>(idat.data()), uLong(idat.size())),
            Z_OK);
  EXPECT_EQ(n, filtered.size());
  std::string prev(row, '\0');
  for (std::uint32_t y = 0; y < d.height; ++y) {
    const std::uint8_t filter = std::uint8_t(filtered[y * (row + 1)]);
    EXPECT_TRUE(filter == 0 || filter == 2) << "row " << y;
    d.raw += '\0';
    std::string cur(row, '\0');
    for (std::size_t i = 0; i < row; ++i)
      cur[i] = char(std::uint8_t(filtered[y * (row + 1) + 1 + i]) + (filter == 2 ? std::uint8_t(prev[i]) : 0));
    d.raw += cur;
    prev = cur;
  }
  return d;
}

Image pattern(int w, int h) {
  Image img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      std::uint8_t* px = img.at(x, y);
      px[0] = std::uint8_t(x * 7 + y);
      px[1] = std::uint8_t(y * 13);
      px[2] = std::uint8_t(x ^ y);
    }
  return img;
}

std::string scanlines(const Image& img) {
  std::string raw;
  for (int y = 0; y < img.height; ++y) {
    raw += '\0';
    raw.append(reinterpret_cast<const char*>(img.at(0, y)), std::size_t(img.width) * 3);
  }
  return raw;
}

TEST(RenderPng, SmallImageRoundTrips) {
  const Image img = pattern(7, 5);
  const Decoded d = decode(encode_png(img));
  EXPECT_EQ(d.width, 7u);
  EXPECT_EQ(d.height, 5u);
  EXPECT_EQ(d.ihdr_tail, std::string("\x08\x02\x00\x00\x00", 5));
  EXPECT_EQ(d.raw, scanlines(img));
}

TEST(RenderPng, LargeImageRoundTripsAndCompresses) {
  const Image img = pattern(300, 200);
  const std::string png = encode_png(img);
  const Decoded d = decode(png);
  EXPECT_LT(png.size(), std::size_t(300 * 200 * 3) / 2);  // the pattern is regular
  EXPECT_EQ(d.width, 300u);
  EXPECT_EQ(d.height, 200u);
  EXPECT_EQ(d.raw, scanlines(img));
}

TEST(RenderPng, WritesTheEncodedBytesToAFile) {
  namespace fs = std::filesystem;
  const fs::path dir =
      fs::temp_directory_path() / ("sphfem_render_png_" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string path = (dir / "picture.png").string();
  const Image img = pattern(33, 17);
  write_png(path, img);
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(bytes, encode_png(img));
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  fs::remove_all(dir);
  EXPECT_THROW(encode_png(Image()), std::invalid_argument);
}

}  // namespace
}  // namespace sphfem::render
