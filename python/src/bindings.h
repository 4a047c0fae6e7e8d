// Pieces of the Python module shared by its source files.
#pragma once

#include <pybind11/pybind11.h>

#include <nlohmann/json_fwd.hpp>
#include <string>

#include "sphfem/scene/spec.h"

namespace sphfem::python {

SceneSpec scene_from(const pybind11::object& scene, const std::string& path);
pybind11::object to_python(const nlohmann::json& j);
void bind_simulation(pybind11::module_& m);

}  // namespace sphfem::python
