#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "gl_program.h"
#include "sphfem/render/headless.h"

namespace sphfem::render {
namespace {

bool has_extension(const char* list, const char* name) {
  if (!list) return false;
  const std::size_t n = std::strlen(name);
  for (const char* p = std::strstr(list, name); p; p = std::strstr(p + 1, name))
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  return false;
}

std::string egl_error(const char* step) {
  char code[16];
  std::snprintf(code, sizeof code, "0x%04x", unsigned(eglGetError()));
  return std::string(step) + " failed (EGL error " + code + ")";
}

// An OpenGL 3.3 core context current on this thread with no surface at all.
class EglContext {
 public:
  EglContext() {
    const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (!client)
      throw GlUnavailable(
          "EGL has no client extensions (EGL 1.5 or EGL_EXT_client_extensions "
          "needed); install libegl-mesa0 and libgl1-mesa-dri");
    std::string tried;
    auto failed = [&](const char* step) { tried += (tried.empty() ? "" : "; ") + egl_error(step); };
    if (has_extension(client, "EGL_MESA_platform_surfaceless")) {
      display_ =
          eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
      if (!initialize()) failed("surfaceless platform: eglInitialize");
    }
    if (!display_ && has_extension(client, "EGL_EXT_platform_device") &&
        has_extension(client, "EGL_EXT_device_enumeration")) {
      EGLDeviceEXT devices[16];
      EGLint count = 0;
      if (eglQueryDevicesEXT(16, devices, &count))
        for (EGLint i = 0; i < count && !display_; ++i) {
          display_ = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
          if (!initialize()) failed("device platform: eglInitialize");
        }
    }
    if (!display_)
      throw GlUnavailable("no headless EGL display: " +
                          (tried.empty() ? std::string("neither EGL_MESA_platform_surfaceless "
                                                       "nor EGL_EXT_platform_device is offered")
                                         : tried) +
                          " (install libegl-mesa0 and libgl1-mesa-dri)");
    if (!eglBindAPI(EGL_OPENGL_API)) throw GlUnavailable(egl_error("eglBindAPI(OpenGL)"));

    const char* ext = eglQueryString(display_, EGL_EXTENSIONS);
    const bool surfaceless = has_extension(ext, "EGL_KHR_surfaceless_context");
    const bool configless = has_extension(ext, "EGL_KHR_no_config_context") ||
                            has_extension(ext, "EGL_MESA_configless_context");
    EGLConfig config = EGL_NO_CONFIG_KHR;
    // A config is needed unless the context can go without one and without a surface.
    if (!configless || !surfaceless) {
      const EGLint want[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE, EGL_PBUFFER_BIT,
                             EGL_NONE};
      EGLint n = 0;
      if (!eglChooseConfig(display_, want, &config, 1, &n) || n < 1)
        throw GlUnavailable(egl_error("eglChooseConfig(OpenGL, pbuffer)"));
    }
    const EGLint attrs[] = {EGL_CONTEXT_MAJOR_VERSION,
                            3,
                            EGL_CONTEXT_MINOR_VERSION,
                            3,
                            EGL_CONTEXT_OPENGL_PROFILE_MASK,
                            EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                            EGL_NONE};
    context_ = eglCreateContext(display_, config, EGL_NO_CONTEXT, attrs);
    if (context_ == EGL_NO_CONTEXT)
      throw GlUnavailable(egl_error("eglCreateContext(OpenGL 3.3 core)"));
    // Without EGL_KHR_surfaceless_context a 1x1 pbuffer stands in; the FBO is drawn to anyway.
    if (!surfaceless) {
      const EGLint pb[] = {EGL_WIDTH, 1, EGL_HEIGHT, 1, EGL_NONE};
      surface_ = eglCreatePbufferSurface(display_, config, pb);
      if (surface_ == EGL_NO_SURFACE) {
        release();
        throw GlUnavailable(egl_error("eglCreatePbufferSurface"));
      }
    }
    if (!make_current()) {
      const std::string why = egl_error("eglMakeCurrent");
      release();
      throw GlUnavailable(why);
    }
  }
  ~EglContext() { release(); }
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  bool make_current() { return eglMakeCurrent(display_, surface_, surface_, context_); }

 private:
  bool initialize() {
    EGLint major = 0, minor = 0;
    if (display_ != EGL_NO_DISPLAY && eglInitialize(display_, &major, &minor)) return true;
    display_ = EGL_NO_DISPLAY;
    return false;
  }
  // The display stays initialised: EGL shares one per platform across the process, and
  // terminating it would pull the rug from under any other renderer still alive.
  void release() {
    if (display_ == EGL_NO_DISPLAY) return;
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (surface_ != EGL_NO_SURFACE) eglDestroySurface(display_, surface_);
    if (context_ != EGL_NO_CONTEXT) eglDestroyContext(display_, context_);
    surface_ = EGL_NO_SURFACE;
    context_ = EGL_NO_CONTEXT;
  }

  EGLDisplay display_ = EGL_NO_DISPLAY;
  EGLContext context_ = EGL_NO_CONTEXT;
  EGLSurface surface_ = EGL_NO_SURFACE;
};

}  // namespace

struct HeadlessRenderer::Impl {
  EglContext context;  // first in, last out: the GL objects below need it current
  std::unique_ptr<FluidRenderer> fluid;
  gl::Texture color;
  gl::Framebuffer target;
};

HeadlessRenderer::HeadlessRenderer() : impl_(std::make_unique<Impl>()) {
  impl_->fluid = std::make_unique<FluidRenderer>();
}

HeadlessRenderer::~HeadlessRenderer() {
  if (!impl_) return;
  impl_->context.make_current();
  impl_->fluid.reset();
}

Image HeadlessRenderer::render(const RenderFrame& frame, const Camera& camera,
                               const FluidStyle& style) {
  Impl& s = *impl_;
  if (camera.width <= 0 || camera.height <= 0)
    throw std::invalid_argument("HeadlessRenderer::render: the camera has an empty image size");
  if (!s.context.make_current()) throw GlUnavailable(egl_error("eglMakeCurrent"));
  s.color.allocate(camera.width, camera.height, GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE);
  s.target.attach("picture", s.color, nullptr);
  s.fluid->render(frame, camera, style, s.target.id());

  Image img(camera.width, camera.height);
  std::vector<std::uint8_t> rgba(std::size_t(camera.width) * camera.height * 4);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, s.target.id());
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glReadPixels(0, 0, camera.width, camera.height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  const GLenum err = glGetError();
  if (err != GL_NO_ERROR)
    throw std::runtime_error("OpenGL error " + std::to_string(err) + " while rendering");
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const std::uint8_t* src = &rgba[(std::size_t(camera.height - 1 - y) * camera.width + x) * 4];
      std::uint8_t* dst = img.at(x, y);
      dst[0] = src[0];
      dst[1] = src[1];
      dst[2] = src[2];
    }
  return img;
}

const FluidRenderer& HeadlessRenderer::passes() const {
  // Its read-backs go to whichever context is current: this renderer's, whatever ran since.
  if (!impl_->context.make_current()) throw GlUnavailable(egl_error("eglMakeCurrent"));
  return *impl_->fluid;
}

std::string HeadlessRenderer::device() const { return impl_->fluid->device(); }

}  // namespace sphfem::render
