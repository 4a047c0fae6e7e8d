// A small seeded mutator for the fuzz tests of the normal suite: the same inputs on every run
// and machine (std::mt19937_64 and integer arithmetic only), so a failure reproduces from its
// seed. libFuzzer (fuzz/) explores further with coverage; this keeps every reader exercised in
// `make test`.
#pragma once

#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace sphfem::fuzz {

using Bytes = std::string;

class Mutator {
 public:
  Mutator(std::uint64_t seed, std::vector<Bytes> seeds) : rng_(seed), seeds_(std::move(seeds)) {}

  // A seed changed in one to four places.
  Bytes next() {
    Bytes b = seeds_.empty() ? Bytes() : seeds_[pick(seeds_.size())];
    const int edits = 1 + int(pick(4));
    for (int i = 0; i < edits; ++i) mutate(b);
    return b;
  }

 private:
  std::size_t pick(std::size_t n) { return n ? std::size_t(rng_() % n) : 0; }

  // Numbers a reader must survive in a count, an index, a size or a coordinate.
  const std::vector<Bytes>& numbers() {
    static const std::vector<Bytes> n = {"0",
                                         "-1",
                                         "1",
                                         "2",
                                         "3",
                                         "4",
                                         "10",
                                         "255",
                                         "65536",
                                         "2147483647",
                                         "2147483648",
                                         "-2147483649",
                                         "4294967295",
                                         "4294967296",
                                         "1e9",
                                         "1e18",
                                         "9223372036854775807",
                                         "18446744073709551615",
                                         "-0",
                                         "1e308",
                                         "-1e308",
                                         "1e-308",
                                         "nan",
                                         "inf",
                                         "-inf",
                                         "0.5",
                                         "1e-12",
                                         "99999999999"};
    return n;
  }
  const std::vector<Bytes>& tokens() {
    static const std::vector<Bytes> t = {"{",
                                         "}",
                                         "[",
                                         "]",
                                         ",",
                                         ":",
                                         "\"",
                                         "//",
                                         "/*",
                                         "*/",
                                         "\n",
                                         " ",
                                         "\0",
                                         "#",
                                         "<",
                                         ">",
                                         "/>",
                                         "=\"",
                                         "\"\"",
                                         "null",
                                         "true",
                                         "false",
                                         "[]",
                                         "{}",
                                         "$Nodes",
                                         "$EndNodes",
                                         "$Elements",
                                         "$EndElements",
                                         "$MeshFormat",
                                         "vertex",
                                         "face",
                                         "element",
                                         "property",
                                         "end_header",
                                         "format",
                                         "binary_little_endian",
                                         "ascii",
                                         "v ",
                                         "f ",
                                         "vn ",
                                         "facet",
                                         "outer loop",
                                         "endloop",
                                         "endfacet",
                                         "solid",
                                         "endsolid",
                                         "<AppendedData",
                                         "encoding=\"raw\"",
                                         "offset=\"",
                                         "NumberOfPoints=\"",
                                         "NumberOfCells=\"",
                                         "&amp;",
                                         "&#",
                                         "\xff\xff\xff\xff",
                                         "\x00\x00\x00\x80",
                                         "\xff\xff\xff\xff\xff\xff\xff\x7f"};
    return t;
  }

  void mutate(Bytes& b) {
    switch (pick(10)) {
      case 0:  // flip a bit
        if (!b.empty()) b[pick(b.size())] ^= char(1u << pick(8));
        break;
      case 1:  // set a byte
        if (!b.empty()) b[pick(b.size())] = char(rng_());
        break;
      case 2: {  // delete a range
        if (b.empty()) break;
        const std::size_t at = pick(b.size());
        b.erase(at, 1 + pick(std::min<std::size_t>(b.size() - at, 32)));
        break;
      }
      case 3: {  // duplicate a range
        if (b.empty() || b.size() > (1u << 20)) break;
        const std::size_t at = pick(b.size());
        const Bytes piece = b.substr(at, 1 + pick(64));
        b.insert(pick(b.size() + 1), piece);
        break;
      }
      case 4:  // insert a token
        b.insert(pick(b.size() + 1), tokens()[pick(tokens().size())]);
        break;
      case 5:
      case 6:
      case 7:
        replace_number(b);
        break;
      case 8:  // cut short
        if (!b.empty()) b.resize(pick(b.size()));
        break;
      case 9: {  // overwrite 4 or 8 bytes with an extreme binary value
        const std::size_t w = pick(2) ? 4 : 8;
        if (b.size() < w) break;
        const std::size_t at = pick(b.size() - w + 1);
        for (std::size_t k = 0; k < w; ++k)
          b[at + k] = char(pick(3) == 0 ? 0 : (pick(2) ? 0xff : char(rng_())));
        break;
      }
    }
  }

  // A number in the text (a run of digits, signs, dots and exponents) becomes another.
  void replace_number(Bytes& b) {
    std::vector<std::pair<std::size_t, std::size_t>> spans;
    auto part = [](char c) { return (c >= '0' && c <= '9') || c == '.' || c == '-' || c == 'e'; };
    for (std::size_t i = 0; i < b.size();) {
      if (b[i] >= '0' && b[i] <= '9') {
        std::size_t s = i;
        if (s > 0 && b[s - 1] == '-') --s;
        std::size_t e = i;
        while (e < b.size() && part(b[e])) ++e;
        spans.push_back({s, e - s});
        i = e;
      } else {
        ++i;
      }
    }
    if (spans.empty()) return;
    const auto [at, len] = spans[pick(spans.size())];
    b.replace(at, len, numbers()[pick(numbers().size())]);
  }

  std::mt19937_64 rng_;
  std::vector<Bytes> seeds_;
};

}  // namespace sphfem::fuzz
