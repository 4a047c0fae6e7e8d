#include "sphfem/io/xml.h"

#include <cctype>

namespace sphfem::io {

std::string xml_escape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string xml_unescape(const std::string& text) {
  static const std::pair<const char*, char> kEntities[] = {
      {"&amp;", '&'}, {"&lt;", '<'}, {"&gt;", '>'}, {"&quot;", '"'}, {"&apos;", '\''}};
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size();) {
    bool matched = false;
    if (text[i] == '&') {
      for (const auto& [ent, c] : kEntities) {
        if (text.compare(i, std::char_traits<char>::length(ent), ent) == 0) {
          out += c;
          i += std::char_traits<char>::length(ent);
          matched = true;
          break;
        }
      }
    }
    if (!matched) out += text[i++];
  }
  return out;
}

std::map<std::string, std::string> xml_attributes(const std::string& tag) {
  std::map<std::string, std::string> attrs;
  std::size_t i = 0;
  auto skip_space = [&] {
    while (i < tag.size() && std::isspace(static_cast<unsigned char>(tag[i]))) ++i;
  };
  // Skip the element name.
  while (i < tag.size() && !std::isspace(static_cast<unsigned char>(tag[i]))) ++i;
  while (true) {
    skip_space();
    std::size_t name_start = i;
    while (i < tag.size() && tag[i] != '=' && tag[i] != '/' &&
           !std::isspace(static_cast<unsigned char>(tag[i])))
      ++i;
    if (i == name_start) break;
    std::string name = tag.substr(name_start, i - name_start);
    skip_space();
    if (i >= tag.size() || tag[i] != '=') break;
    ++i;
    skip_space();
    if (i >= tag.size() || (tag[i] != '"' && tag[i] != '\'')) break;
    char quote = tag[i++];
    std::size_t end = tag.find(quote, i);
    if (end == std::string::npos) break;
    attrs[name] = xml_unescape(tag.substr(i, end - i));
    i = end + 1;
  }
  return attrs;
}

}  // namespace sphfem::io
