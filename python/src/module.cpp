// The Python module sphfem._sphfem: scenes, the Simulation class and the errors (docs/python.md).
// Errors keep the core's messages, which are the CLI's.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <nlohmann/json.hpp>

#include "bindings.h"
#include "sphfem/couple/ray_coupling.h"
#include "sphfem/scene/load.h"
#include "sphfem/sim/checkpoint.h"
#include "sphfem/sph/solver.h"

namespace py = pybind11;

namespace sphfem::python {

// A scene file (str or os.PathLike) or a dict in the scene-file format; `path` names a dict's
// scene in messages and is the folder its relative mesh files start from.
SceneSpec scene_from(const py::object& scene, const std::string& path) {
  if (py::isinstance<py::dict>(scene)) {
    const std::string text = py::module_::import("json")
                                 .attr("dumps")(scene, py::arg("allow_nan") = false)
                                 .cast<std::string>();
    SceneSpec spec = parse_scene(nlohmann::json::parse(text), path);
    validate_scene(spec, path);
    return spec;
  }
  const py::object fspath = py::module_::import("os").attr("fspath");
  return load_scene(fspath(scene).cast<std::string>());
}

// The scene-file JSON as Python objects.
py::object to_python(const nlohmann::json& j) {
  return py::module_::import("json").attr("loads")(j.dump());
}

}  // namespace sphfem::python

PYBIND11_MODULE(_sphfem, m) {
  using namespace sphfem;
  using namespace sphfem::python;
  m.doc() = "sphfem: SPH fluid coupled with FEM soft bodies (docs/python.md)";

  // What the CLI reports with exit code 2 (bad input) and 3 (unstable run).
  static py::exception<SceneError> scene_error(m, "SceneError", PyExc_ValueError);
  static py::exception<CheckpointError> checkpoint_error(m, "CheckpointError", PyExc_RuntimeError);
  static py::exception<SimulationError> simulation_error(m, "SimulationError", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const SceneError& e) { scene_error(e.what()); } catch (const CheckpointError& e) {
      checkpoint_error(e.what());
    } catch (const SimulationError& e) {
      simulation_error(e.what());
    } catch (const BodyStepError& e) { simulation_error(e.what()); }
  });

  m.def(
      "load_scene",
      [](const py::object& path) {
        const std::string p = py::module_::import("os").attr("fspath")(path).cast<std::string>();
        return to_python(scene_to_json(load_scene(p)));
      },
      py::arg("path"),
      "Reads and validates a scene file; returns it as a dict with every field written, which "
      "Simulation() takes back (raises SceneError naming the file, the field and the fix).");

  bind_simulation(m);
}
