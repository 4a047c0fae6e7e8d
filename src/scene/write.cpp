// Writing a scene: scene_to_json and the scene-file layout (scene/write.h).
#include "scene/write.h"

#include <algorithm>
#include <cstddef>

#include "scene/messages.h"
#include "sphfem/scene/load.h"

namespace sphfem {

namespace scene {
namespace {

std::string pad(int indent) { return std::string(static_cast<std::size_t>(indent), ' '); }

}  // namespace

void pretty(const nlohmann::ordered_json& v, int indent, std::string& out) {
  if (v.is_object() && !v.empty()) {
    out += "{\n";
    std::size_t i = 0;
    for (auto it = v.begin(); it != v.end(); ++it, ++i) {
      out += pad(indent + 2) + scene_text::in_quotes(it.key()) + ": ";
      pretty(*it, indent + 2, out);
      out += i + 1 < v.size() ? ",\n" : "\n";
    }
    out += pad(indent) + "}";
  } else if (v.is_array() && std::any_of(v.begin(), v.end(), [](const nlohmann::ordered_json& e) {
               return e.is_structured();
             })) {
    out += "[\n";
    for (std::size_t i = 0; i < v.size(); ++i) {
      out += pad(indent + 2);
      pretty(v[i], indent + 2, out);
      out += i + 1 < v.size() ? ",\n" : "\n";
    }
    out += pad(indent) + "]";
  } else {
    out += format_value(nlohmann::json::parse(v.dump()));
  }
}

}  // namespace scene

nlohmann::json scene_to_json(const SceneSpec& scene) {
  return scene::to_json<nlohmann::json>(scene::scene_table(), &scene);
}

}  // namespace sphfem
