// Parsing: JSON -> SceneSpec field by field following the field table (scene/fields.cpp),
// with type errors that say what was expected and a "did you mean" for misspelt names.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "scene/field_checks.h"
#include "scene/messages.h"
#include "sphfem/scene/fields.h"
#include "sphfem/scene/load.h"

namespace sphfem {
namespace {

using nlohmann::json;
using scene::check_number;
using scene::example;
using scene::Field;
using scene::FieldType;
using scene::format_value;
using scene::ObjectTable;
using scene::unit_suffix;
using namespace scene_text;

// What a JSON value is, for "got ..." in type errors.
std::string describe(const json& v) {
  switch (v.type()) {
    case json::value_t::null:
      return "null";
    case json::value_t::boolean:
      return std::string("a boolean (") + (v.get<bool>() ? "true" : "false") + ")";
    case json::value_t::number_integer:
    case json::value_t::number_unsigned:
    case json::value_t::number_float:
      return "a number (" + format_value(v) + ")";
    case json::value_t::string: {
      std::string s = v.get<std::string>();
      if (s.size() > 40) s = s.substr(0, 37) + "...";
      return "a string (" + in_quotes(s) + ")";
    }
    case json::value_t::array:
      return "an array of " + std::to_string(v.size()) + (v.size() == 1 ? " element" : " elements");
    case json::value_t::object:
      return "an object";
    default:
      return "an unsupported value";
  }
}

std::string expected(const Field& f) {
  switch (f.type) {
    case FieldType::Number:
      return "a number" + unit_suffix(f);
    case FieldType::Integer:
      return "an integer" + unit_suffix(f);
    case FieldType::IntegerList:
      return "an array of integers [i, j, ...]";
    case FieldType::Bool:
      return "true or false";
    case FieldType::String:
      return "a string";
    case FieldType::Enum:
      return "one of " + in_quotes_list(f.choices);
    case FieldType::Vec3:
      return "an array of 3 numbers [x, y, z]" + unit_suffix(f);
    case FieldType::Object:
      return "an object {...}";
    case FieldType::ObjectArray:
      return "an array of objects [{...}, ...]";
  }
  return "a value";
}

std::string type_fix(const Field& f) {
  switch (f.type) {
    case FieldType::Number:
      return "write a number without quotes, e.g. " + example(f);
    case FieldType::Integer:
      return "write a whole number without quotes, e.g. " + example(f);
    case FieldType::IntegerList:
      return "write whole numbers in brackets, e.g. [0, 1], or [] for none";
    case FieldType::Bool:
      return "write true or false without quotes";
    case FieldType::String:
      return "write text in double quotes";
    case FieldType::Enum:
      return "write one of " + in_quotes_list(f.choices);
    case FieldType::Vec3:
      return "write three numbers, e.g. " + example(f);
    case FieldType::Object:
      return "write the section as an object, e.g. " + in_quotes(f.key) + ": {...}";
    case FieldType::ObjectArray:
      return "write a list of objects, e.g. " + in_quotes(f.key) + ": [{...}], or [] for none";
  }
  return "see docs/scene-format.md";
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Edit distance counting a swap of neighbours as one edit (typos like "visocsity").
std::size_t edit_distance(const std::string& a, const std::string& b) {
  const std::size_t m = a.size(), k = b.size();
  std::vector<std::vector<std::size_t>> d(m + 1, std::vector<std::size_t>(k + 1));
  for (std::size_t i = 0; i <= m; ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= k; ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= m; ++i) {
    for (std::size_t j = 1; j <= k; ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[m][k];
}

// The allowed name nearest to a misspelt one, if any is plausibly meant.
std::optional<std::string> closest(const std::string& word, const std::vector<std::string>& names) {
  const std::string w = lower(word);
  std::optional<std::string> best;
  std::size_t best_d = SIZE_MAX;
  for (const std::string& name : names) {
    const std::string c = lower(name);
    std::size_t d = edit_distance(w, c);
    const bool contains = c.size() >= 3 && w.find(c) != std::string::npos;
    if (contains) d = std::min<std::size_t>(d, 1);
    const std::size_t limit = std::max<std::size_t>(2, c.size() / 3);
    if (d <= limit && d < c.size() && d < best_d) {
      best = name;
      best_d = d;
    }
  }
  return best;
}

// Reads JSON into spec structs following the field table.
class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  void object(const ObjectTable& t, const json& j, void* owner, const std::string& at,
              std::size_t index) {
    // Unknown keys first: a misspelt key is the likeliest cause of any later surprise.
    for (auto it = j.begin(); it != j.end(); ++it)
      if (!t.find(it.key())) unknown(t, it.key(), at);
    for (const Field& f : t.fields) {
      auto it = j.find(f.key);
      if (it != j.end()) field(f, *it, owner, join(at, f.key));
    }
    if (t.finish) t.finish(owner, index);
  }

 private:
  [[noreturn]] void unknown(const ObjectTable& t, const std::string& key, const std::string& at) {
    const std::vector<std::string> keys = t.keys();
    std::optional<std::string> guess = closest(key, keys);
    fail(file_, join(at, key), "unknown field",
         guess ? "did you mean " + in_quotes(*guess) + "?"
               : "the fields allowed here are " + in_quotes_list(keys));
  }

  [[noreturn]] void wrong_type(const Field& f, const json& v, const std::string& at) {
    fail(file_, at, "expected " + expected(f) + ", got " + describe(v), type_fix(f));
  }

  void field(const Field& f, const json& v, void* owner, const std::string& at) {
    switch (f.type) {
      case FieldType::Number:
      case FieldType::Integer:
        if (!v.is_number()) wrong_type(f, v, at);
        check_number(f, v.get<double>(), at, file_);
        store(f, owner, json(v.get<double>()), at);
        return;
      case FieldType::IntegerList:
        if (!v.is_array()) wrong_type(f, v, at);
        for (std::size_t i = 0; i < v.size(); ++i) {
          if (!v[i].is_number())
            fail(file_, indexed(at, i), "expected an integer, got " + describe(v[i]), type_fix(f));
          check_number(f, v[i].get<double>(), indexed(at, i), file_);
        }
        store(f, owner, v, at);
        return;
      case FieldType::Bool:
        if (!v.is_boolean()) wrong_type(f, v, at);
        store(f, owner, v, at);
        return;
      case FieldType::String:
        if (!v.is_string()) wrong_type(f, v, at);
        store(f, owner, v, at);
        return;
      case FieldType::Enum:
        enumeration(f, v, owner, at);
        return;
      case FieldType::Vec3:
        vector3(f, v, owner, at);
        return;
      case FieldType::Object:
        if (!v.is_object()) wrong_type(f, v, at);
        object(*f.table, v, f.child(owner), at, 0);
        return;
      case FieldType::ObjectArray:
        if (!v.is_array()) wrong_type(f, v, at);
        f.resize(owner, v.size());
        for (std::size_t i = 0; i < v.size(); ++i) {
          const std::string item = indexed(at, i);
          if (!v[i].is_object())
            fail(file_, item, "expected an object {...}, got " + describe(v[i]),
                 "write each entry of " + f.key + " as an object in braces");
          object(*f.table, v[i], f.element(owner, i), item, i);
        }
        return;
    }
  }

  void enumeration(const Field& f, const json& v, void* owner, const std::string& at) {
    if (!v.is_string()) wrong_type(f, v, at);
    const std::string name = v.get<std::string>();
    if (std::find(f.choices.begin(), f.choices.end(), name) == f.choices.end()) {
      std::optional<std::string> guess = closest(name, f.choices);
      fail(file_, at, "unknown " + f.key + " " + in_quotes(name),
           guess ? "did you mean " + in_quotes(*guess) + "? the allowed names are " +
                       in_quotes_list(f.choices)
                 : "use one of " + in_quotes_list(f.choices));
    }
    store(f, owner, v, at);
  }

  void vector3(const Field& f, const json& v, void* owner, const std::string& at) {
    if (!v.is_array() || v.size() != 3) wrong_type(f, v, at);
    json values = json::array();
    for (std::size_t i = 0; i < 3; ++i) {
      const std::string item = indexed(at, i);
      if (!v[i].is_number())
        fail(file_, item, "expected a number" + unit_suffix(f) + ", got " + describe(v[i]),
             "write three numbers without quotes, e.g. " + example(f));
      const double x = v[i].get<double>();
      if (!std::isfinite(x))
        fail(file_, item, "must be a finite number (got " + num(x) + ")",
             "write three ordinary numbers, e.g. " + example(f));
      values.push_back(x);
    }
    store(f, owner, values, at);
  }

  void store(const Field& f, void* owner, const json& v, const std::string& at) {
    try {
      f.set(owner, v);
    } catch (const scene::FieldError& e) { fail(file_, at, e.what(), e.fix); }
  }

  std::string file_;
};

}  // namespace

SceneSpec parse_scene(const nlohmann::json& scene, const std::string& path) {
  if (!scene.is_object())
    fail(path, "", "expected a JSON object {...}, got " + describe(scene),
         "write the scene as an object, e.g. {\"fluid\": {\"blocks\": [...]}}");
  SceneSpec spec;
  Reader(path).object(scene::scene_table(), scene, &spec, "", 0);
  spec.path = path;
  return spec;
}

}  // namespace sphfem
