#include "sphfem/render/image.h"

#include <algorithm>
#include <array>
#include <stdexcept>

#include <zlib.h>

#include "sphfem/io/atomic_file.h"

namespace sphfem::render {
namespace {

void put_be32(std::string& out, std::uint32_t v) {
  out += char(v >> 24);
  out += char(v >> 16);
  out += char(v >> 8);
  out += char(v);
}

// Length, type, data, then the CRC over type and data (PNG spec, section 5.3).
void put_chunk(std::string& out, const char type[4], const std::string& data) {
  put_be32(out, std::uint32_t(data.size()));
  const std::size_t start = out.size();
  out.append(type, 4);
  out += data;
  put_be32(out, std::uint32_t(::crc32(0, reinterpret_cast<const Bytef*>(out.data() + start),
                                       uInt(out.size() - start))));
}

// Deflate through zlib; the "Up" filter on every row makes smooth pictures compress well.
std::string deflate(const std::string& raw) {
  uLongf n = compressBound(uLong(raw.size()));
  std::string z(n, '\0');
  if (compress2(reinterpret_cast<Bytef*>(z.data()), &n,
                reinterpret_cast<const Bytef*>(raw.data()), uLong(raw.size()), 6) != Z_OK)
    throw std::runtime_error("encode_png: zlib could not compress the picture");
  z.resize(n);
  return z;
}

}  // namespace

std::string encode_png(const Image& image) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgb.size() != std::size_t(image.width) * std::size_t(image.height) * 3)
    throw std::invalid_argument(
        "encode_png: image is empty or its pixel buffer has the wrong size");
  const std::size_t row = std::size_t(image.width) * 3;
  std::string raw;
  raw.reserve((row + 1) * image.height);
  for (int y = 0; y < image.height; ++y) {
    raw += char(2);  // filter type Up: each byte minus the one above it
    const std::uint8_t* cur = image.at(0, y);
    const std::uint8_t* up = y > 0 ? image.at(0, y - 1) : nullptr;
    for (std::size_t i = 0; i < row; ++i) raw += char(std::uint8_t(cur[i] - (up ? up[i] : 0)));
  }

  std::string ihdr;
  put_be32(ihdr, std::uint32_t(image.width));
  put_be32(ihdr, std::uint32_t(image.height));
  ihdr += char(8);               // bit depth
  ihdr += char(2);               // colour type: truecolour
  ihdr += std::string(3, '\0');  // compression, filter, interlace

  std::string png("\x89PNG\r\n\x1a\n", 8);
  put_chunk(png, "IHDR", ihdr);
  put_chunk(png, "IDAT", deflate(raw));
  put_chunk(png, "IEND", std::string());
  return png;
}

void write_png(const std::string& path, const Image& image) {
  io::write_file_atomic(path, encode_png(image));
}

}  // namespace sphfem::render
