// The little XML the frame files need: escaping attribute values and reading back the
// attributes of a start tag written by this library.
#pragma once

#include <map>
#include <string>

namespace sphfem::io {

std::string xml_escape(const std::string& text);
std::string xml_unescape(const std::string& text);

// Attributes of one start tag, given the text between '<' and '>' (e.g.
// `DataArray type="Float32" Name="p"`). Both quote styles are accepted.
std::map<std::string, std::string> xml_attributes(const std::string& tag);

}  // namespace sphfem::io
