// sphfem.Simulation: a scene built and stepped from Python, its state read as NumPy arrays.
//
// Which arrays are copies: the fluid's (positions, velocities, densities, pressures, ids) are
// views of one snapshot per state, the one `sphfem run` writes to its frames (the solver
// re-sorts its own arrays every step and computes densities for it), so they stay as they were
// when read, however the simulation goes on or ends. Body node positions and velocities are
// live views of the solver's own arrays on the CPU backend (copies under CUDA): they follow the
// simulation as it steps and keep it alive while they exist. Gauges and rest positions are
// copies. Every array is read-only.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bindings.h"
#include "session.h"
#include "sphfem/core/backend.h"
#include "sphfem/scene/bodies.h"
#include "sphfem/scene/load.h"

namespace py = pybind11;

namespace sphfem::python {

namespace {

// A read-only array over memory that `owner` keeps alive.
template <class T>
py::array_t<T> view(const T* data, std::vector<py::ssize_t> shape, py::handle owner) {
  py::array_t<T> a(shape, data, owner);
  a.attr("setflags")(py::arg("write") = false);
  return a;
}

// An (n, 3) view of Vec3s (3 Reals each, no padding).
py::array_t<Real> vec3_view(const Vec3* data, int n, py::handle owner) {
  static_assert(sizeof(Vec3) == 3 * sizeof(Real), "Vec3 is three packed Reals");
  return view<Real>(reinterpret_cast<const Real*>(data), {py::ssize_t(n), 3}, owner);
}

// A capsule holding a snapshot alive for the arrays made from it.
py::capsule keep(std::shared_ptr<const FluidSnapshot> s) {
  auto* p = new std::shared_ptr<const FluidSnapshot>(std::move(s));
  return py::capsule(p,
                     [](void* q) { delete static_cast<std::shared_ptr<const FluidSnapshot>*>(q); });
}

// A str or os.PathLike as a path.
std::string fspath(const py::object& path) {
  return py::module_::import("os").attr("fspath")(path).cast<std::string>();
}

Backend backend_named(const std::string& name) {
  if (name == "cpu") return Backend::Cpu;
  if (name == "cuda") return Backend::Cuda;
  throw std::invalid_argument("backend '" + name + "': use \"cpu\" or \"cuda\"");
}

int body_named(Simulation& sim, const py::object& body) {
  if (py::isinstance<py::int_>(body)) return body.cast<int>();
  const std::string name = body.cast<std::string>();
  const int b = body_index(sim.scene(), name);
  if (b < 0) {
    std::string names;
    for (const BodySpec& s : sim.scene().bodies) names += (names.empty() ? "" : ", ") + s.name;
    throw py::key_error("body '" + name + "': the scene's bodies are " +
                        (names.empty() ? "none" : names));
  }
  return b;
}

py::dict step_info(const StepInfo& s) {
  py::dict d;
  d["dt"] = s.dt;
  d["pressure_iterations"] = s.pressure_iterations;
  d["divergence_iterations"] = s.divergence_iterations;
  d["density_error"] = s.density_error;
  d["clamped"] = s.clamped;
  d["emitted"] = s.emitted;
  return d;
}

template <class F>
py::array_t<Real> fluid_vec3(Session& s, F member) {
  std::shared_ptr<const FluidSnapshot> f = s.fluid();
  const std::vector<Vec3>& v = (*f).*member;
  return vec3_view(v.data(), f->n, keep(f));
}

template <class T, class F>
py::array_t<T> fluid_scalar(Session& s, F member) {
  std::shared_ptr<const FluidSnapshot> f = s.fluid();
  const auto& v = (*f).*member;
  return view<T>(reinterpret_cast<const T*>(v.data()), {py::ssize_t(f->n)}, keep(f));
}

// Body node arrays: live views on the host, copies from a device.
py::array_t<Real> body_vec3(Session& s, py::handle self, bool velocities) {
  BodySolver* b = s.sim().bodies();
  if (!b) return py::array_t<Real>(std::vector<py::ssize_t>{0, 3});
  const BodyArrays a = b->arrays();
  if (a.space == MemSpace::Host) return vec3_view(velocities ? a.v : a.x, a.nodes, self);
  const BodySnapshot snap = s.bodies();
  const std::vector<Vec3>& v = velocities ? snap.v : snap.x;
  return py::array_t<Real>(std::vector<py::ssize_t>{py::ssize_t(snap.n), 3},
                           reinterpret_cast<const Real*>(v.data()));
}

}  // namespace

void bind_simulation(py::module_& m) {
  py::class_<Session>(m, "Simulation", R"doc(
A scene built and ready to step.

Simulation(scene, backend="cpu", threads=0, path="<dict>"): scene is a scene file's path or a
dict in the scene-file format (docs/scene-format.md; `path` then names it in messages and is the
folder its relative mesh files start from). Raises SceneError with the CLI's message (file,
JSON path of the field, fix) for a bad scene.
)doc")
      .def(py::init([](const py::object& scene, const std::string& backend, int threads,
                       const std::string& path) {
             if (threads > 0) set_cpu_threads(threads);
             const SceneSpec spec = scene_from(scene, path);
             return std::make_unique<Session>(spec, backend_named(backend));
           }),
           py::arg("scene"), py::arg("backend") = "cpu", py::arg("threads") = 0,
           py::arg("path") = "<dict>")
      .def(
          "step",
          [](Session& s, double dt) {
            StepInfo info;
            {
              py::gil_scoped_release free;
              info = s.step(dt);
            }
            return step_info(info);
          },
          py::arg("dt") = 0.0,
          "One step of at most dt seconds (0: the solver's own limit), ending no later than "
          "the next frame time (1 / output.fps); returns the step's dt, iterations and counts.")
      .def(
          "advance",
          [](Session& s, double seconds) {
            py::gil_scoped_release free;
            return s.advance(seconds);
          },
          py::arg("seconds"),
          "Steps until `seconds` more have passed, as `sphfem run` steps a run of that length "
          "(same steps, same bits); returns the number of steps.")
      .def_property_readonly(
          "time", [](Session& s) { return s.sim().time(); }, "s")
      .def_property_readonly("steps", [](Session& s) { return s.sim().steps(); })
      .def_property_readonly(
          "scene", [](Session& s) { return to_python(scene_to_json(s.sim().scene())); },
          "The scene as a dict with every field written.")
      .def_property_readonly("n_particles", [](Session& s) { return s.fluid()->n; })
      .def_property_readonly(
          "positions", [](Session& s) { return fluid_vec3(s, &FluidSnapshot::x); },
          "(n, 3) particle positions, m (a view of this state's snapshot, see the module doc)")
      .def_property_readonly(
          "velocities", [](Session& s) { return fluid_vec3(s, &FluidSnapshot::v); }, "(n, 3) m/s")
      .def_property_readonly(
          "densities", [](Session& s) { return fluid_scalar<Real>(s, &FluidSnapshot::rho); },
          "(n,) kg/m^3, with the near-surface density, as the frames have them")
      .def_property_readonly(
          "pressures", [](Session& s) { return fluid_scalar<Real>(s, &FluidSnapshot::p); },
          "(n,) Pa")
      .def_property_readonly(
          "ids", [](Session& s) { return fluid_scalar<std::uint32_t>(s, &FluidSnapshot::id); },
          "(n,) stable particle names (the order of the arrays changes from step to step)")
      .def_property_readonly(
          "body_positions",
          [](py::object self) { return body_vec3(self.cast<Session&>(), self, false); },
          "(nodes, 3) all bodies' node positions, m, in model order (a live view on the CPU)")
      .def_property_readonly(
          "body_velocities",
          [](py::object self) { return body_vec3(self.cast<Session&>(), self, true); },
          "(nodes, 3) m/s (a live view on the CPU)")
      .def_property_readonly(
          "rest_positions",
          [](Session& s) {
            const std::vector<Vec3>& x0 = s.sim().bodies_model().x0;
            return py::array_t<Real>(std::vector<py::ssize_t>{py::ssize_t(x0.size()), 3},
                                     reinterpret_cast<const Real*>(x0.data()));
          },
          "(nodes, 3) the bodies' rest node positions (a copy)")
      .def_property_readonly("bodies",
                             [](Session& s) {
                               std::vector<std::string> names;
                               for (const BodySpec& b : s.sim().scene().bodies)
                                 names.push_back(b.name);
                               return names;
                             })
      .def(
          "body_nodes",
          [](Session& s, const py::object& body) {
            const int b = body_named(s.sim(), body);
            const BodiesModel& m = s.sim().bodies_model();
            if (b < 0 || std::size_t(b) >= m.bodies.size())
              throw py::index_error("body " + std::to_string(b) + ": the scene has " +
                                    std::to_string(m.bodies.size()) + " bodies");
            return py::slice(m.node_offset[std::size_t(b)], m.node_offset[std::size_t(b) + 1], 1);
          },
          py::arg("body"), "The slice of body_positions that holds a body's nodes (name or index).")
      .def(
          "pinned_nodes",
          [](Session& s, const py::object& body) {
            const std::vector<int> n = s.sim().pinned_nodes(body_named(s.sim(), body));
            return py::array_t<int>(py::ssize_t(n.size()), n.data());
          },
          py::arg("body"), "Global indices of a body's pinned nodes (into body_positions).")
      .def(
          "move_pinned",
          [](Session& s, const std::vector<int>& nodes, const py::array_t<double>& x) {
            if (x.ndim() != 2 || x.shape(1) != 3)
              throw std::invalid_argument("move_pinned: positions must be an (n, 3) array");
            std::vector<Vec3d> p(std::size_t(x.shape(0)));
            auto r = x.unchecked<2>();
            for (py::ssize_t i = 0; i < x.shape(0); ++i)
              p[std::size_t(i)] = Vec3d(r(i, 0), r(i, 1), r(i, 2));
            s.move_pinned(nodes, p);
          },
          py::arg("nodes"), py::arg("positions"),
          "Moves pinned nodes (global indices) to positions (n, 3) before the next step: "
          "kinematic control, such as a tool pushing the body. Move a few mm at a time.")
      .def(
          "set_emitter", [](Session& s, int e, bool on) { s.sim().set_emitter_enabled(e, on); },
          py::arg("index"), py::arg("on"),
          "Turns fluid.emitters[index] on or off (a valve on its start..end window).")
      .def(
          "emitter_on", [](Session& s, int e) { return s.sim().emitter_enabled(e); },
          py::arg("index"))
      .def_property_readonly(
          "gauges",
          [](Session& s) {
            const GaugeSeries& g = s.gauges();
            py::dict d;
            for (std::size_t c = 0; c < g.columns().size(); ++c) {
              const std::vector<double>& v = g.column(c);
              d[py::str(g.columns()[c])] = py::array_t<double>(py::ssize_t(v.size()), v.data());
            }
            return d;
          },
          "The gauges at every frame time so far (frame 0 is the start), as a dict of arrays "
          "under gauges.csv's column names (copies).")
      .def(
          "write_frame",
          [](Session& s, const py::object& dir) { return s.write_frame(fspath(dir)); },
          py::arg("out_dir"),
          "Writes the present state's frames (out_dir/frames/*_NNNNNN.vtu, .ply when "
          "output.ply) and out_dir/run.json; returns the files written.")
      .def(
          "save", [](const Session& s, const py::object& path) { s.save(fspath(path)); },
          py::arg("path"), "Writes the state to a checkpoint file.")
      .def(
          "load", [](Session& s, const py::object& path) { s.load(fspath(path)); }, py::arg("path"),
          "Continues from a checkpoint file of the same scene, bit for bit; raises "
          "CheckpointError for another scene's or a damaged file.")
      .def("state_hash", &Session::state_hash,
           "The state's hash, as `sphfem run` prints it for its final state.");
}

}  // namespace sphfem::python
