// A build without the OpenGL renderer (SPHFEM_ENABLE_GL=OFF): the headless renderer reports
// itself unavailable, so `sphfem render` falls back to the software renderer.
#include "sphfem/render/headless.h"

namespace sphfem::render {
namespace {

GlUnavailable not_built() {
  return GlUnavailable(
      "this sphfem was built without the OpenGL renderer (SPHFEM_ENABLE_GL=OFF); run "
      "scripts/install-deps.sh and reconfigure");
}

}  // namespace

struct HeadlessRenderer::Impl {};

HeadlessRenderer::HeadlessRenderer() { throw not_built(); }
HeadlessRenderer::~HeadlessRenderer() = default;
Image HeadlessRenderer::render(const RenderFrame&, const Camera&, const FluidStyle&) {
  throw not_built();
}
const FluidRenderer& HeadlessRenderer::passes() const { throw not_built(); }
std::string HeadlessRenderer::device() const { throw not_built(); }

}  // namespace sphfem::render
