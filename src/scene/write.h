// The scene as JSON: the spec walked in field-table order, and the scene-file layout. Shared
// by scene_to_json (write.cpp) and the example in the format docs (docs.cpp).
#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>

#include "sphfem/scene/fields.h"

namespace sphfem::scene {

// The spec as JSON in table order; J is json (sorted keys) or ordered_json (for the docs).
template <class J>
J to_json(const ObjectTable& t, const void* owner) {
  void* mutable_owner = const_cast<void*>(owner);  // accessors are shared with the reader
  J out = J::object();
  for (const Field& f : t.fields) {
    if (f.type == FieldType::Object) {
      out[f.key] = to_json<J>(*f.table, f.child(mutable_owner));
    } else if (f.type == FieldType::ObjectArray) {
      J items = J::array();
      for (std::size_t i = 0; i < f.count(owner); ++i)
        items.push_back(to_json<J>(*f.table, f.element(mutable_owner, i)));
      out[f.key] = items;
    } else {
      out[f.key] = J(f.get(owner));
    }
  }
  return out;
}

// Scene-file layout: one field per line, vectors and other scalar lists on one line.
void pretty(const nlohmann::ordered_json& v, int indent, std::string& out);

}  // namespace sphfem::scene
