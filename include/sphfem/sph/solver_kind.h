// Which pressure solver the fluid runs. Its own header so that the scene (scene/spec.h) can
// name it without the fluid model, and the fluid never includes the scene.
#pragma once

namespace sphfem {

enum class SolverKind { WCSPH, DFSPH };

}  // namespace sphfem
