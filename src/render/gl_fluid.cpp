// The passes of fluid_gl.h, in the order they run in FluidRenderer::render.
#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

#include "gl_program.h"
#include "gl_shaders.h"
#include "sphfem/render/fluid_gl.h"
#include "sphfem/render/font.h"

namespace sphfem::render {
namespace {

using gl::Framebuffer;
using gl::Program;
using gl::Texture;

// Light neutral surroundings, so that blue reads as water and warm colours as bodies.
const Vec3d kSkyZenith{0.55, 0.68, 0.84}, kSkyHorizon{0.90, 0.92, 0.95}, kGround{0.66, 0.66, 0.64};
const Vec3d kFloorColor{0.80, 0.80, 0.78}, kWallColor{0.84, 0.85, 0.86},
    kEdgeColor{0.22, 0.24, 0.28};
const Vec3d kWaterBody{0.02, 0.15, 0.30}, kParticleColor{0.20, 0.50, 0.85};
const Vec3d kWireColor{0.10, 0.10, 0.12};

std::string source(const char* a, const char* b = "", const char* c = "") {
  return std::string(gl::kVersion) + a + b + c;
}

// Spacing of the floor grid: the largest of 1, 2, 5 x 10^k giving at least six cells.
double grid_spacing(double extent) {
  if (!(extent > 0)) return 1;
  const double base = std::pow(10.0, std::floor(std::log10(extent)));
  for (double g : {base, base / 2, base / 5, base / 10, base / 20, base / 50})
    if (extent / g >= 6) return g;
  return base / 100;
}

enum class Kind { Floor, Wall, Mesh, Edge };

// Everything opaque of the scene pass in one indexed buffer of (position, normal) vertices.
struct Geometry {
  struct Draw {
    Kind kind;
    GLenum mode;
    std::size_t first, count;  // in indices
    Vec3d color;
  };
  std::vector<float> vertices;
  std::vector<std::uint32_t> indices;
  std::vector<Draw> draws;

  std::uint32_t vertex(const Vec3d& p, const Vec3d& n) {
    for (int k = 0; k < 3; ++k) vertices.push_back(float(p[k]));
    for (int k = 0; k < 3; ++k) vertices.push_back(float(n[k]));
    return std::uint32_t(vertices.size() / 6 - 1);
  }
  // A quad a, b, c, d (in order around it) as two triangles.
  void quad(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d, const Vec3d& n) {
    const std::uint32_t i = vertex(a, n), j = vertex(b, n), k = vertex(c, n), l = vertex(d, n);
    indices.insert(indices.end(), {i, j, k, i, k, l});
  }
  void begin() { draws.push_back({Kind::Floor, GL_TRIANGLES, indices.size(), 0, {}}); }
  void end(Kind kind, GLenum mode, const Vec3d& color) {
    Draw& d = draws.back();
    d.kind = kind;
    d.mode = mode;
    d.count = indices.size() - d.first;
    d.color = color;
    if (d.count == 0) draws.pop_back();
  }
};

Geometry build_geometry(const RenderFrame& frame, const FluidStyle& style, const Camera& cam,
                        const Vec3d& lo, const Vec3d& hi, double reach) {
  Geometry g;
  if (style.floor) {
    const double y = lo.y, cx = 0.5 * (lo.x + hi.x), cz = 0.5 * (lo.z + hi.z);
    g.begin();
    g.quad(Vec3d(cx - reach, y, cz - reach), Vec3d(cx - reach, y, cz + reach),
           Vec3d(cx + reach, y, cz + reach), Vec3d(cx + reach, y, cz - reach), Vec3d(0, 1, 0));
    g.end(Kind::Floor, GL_TRIANGLES, kFloorColor);
  }
  if (style.tank && frame.has_box) {
    const Vec3d a = vmin(frame.box_lo, frame.box_hi), b = vmax(frame.box_lo, frame.box_hi);
    // Only the walls whose inside faces the camera: the near ones would hide the water.
    g.begin();
    if (cam.eye.x > a.x)
      g.quad(Vec3d(a.x, a.y, a.z), Vec3d(a.x, b.y, a.z), Vec3d(a.x, b.y, b.z), Vec3d(a.x, a.y, b.z),
             Vec3d(1, 0, 0));
    if (cam.eye.x < b.x)
      g.quad(Vec3d(b.x, a.y, a.z), Vec3d(b.x, a.y, b.z), Vec3d(b.x, b.y, b.z), Vec3d(b.x, b.y, a.z),
             Vec3d(-1, 0, 0));
    if (cam.eye.z > a.z)
      g.quad(Vec3d(a.x, a.y, a.z), Vec3d(b.x, a.y, a.z), Vec3d(b.x, b.y, a.z), Vec3d(a.x, b.y, a.z),
             Vec3d(0, 0, 1));
    if (cam.eye.z < b.z)
      g.quad(Vec3d(a.x, a.y, b.z), Vec3d(a.x, b.y, b.z), Vec3d(b.x, b.y, b.z), Vec3d(b.x, a.y, b.z),
             Vec3d(0, 0, -1));
    g.end(Kind::Wall, GL_TRIANGLES, kWallColor);
    g.begin();
    std::uint32_t corner[8];
    for (int i = 0; i < 8; ++i)
      corner[i] =
          g.vertex(Vec3d(i & 1 ? b.x : a.x, i & 2 ? b.y : a.y, i & 4 ? b.z : a.z), Vec3d(0, 1, 0));
    for (int i = 0; i < 8; ++i)
      for (int bit : {1, 2, 4})
        if (!(i & bit)) g.indices.insert(g.indices.end(), {corner[i], corner[i | bit]});
    g.end(Kind::Edge, GL_LINES, kEdgeColor);
  }
  if (style.meshes || style.wireframe)
    for (const TriangleMesh& m : frame.meshes) {
      const std::vector<float> normals = smooth_normals(m);
      const std::uint32_t base = std::uint32_t(g.vertices.size() / 6);
      const std::size_t nv = m.positions.size() / 3;
      for (std::size_t v = 0; v < nv; ++v)
        g.vertex(Vec3d(m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]),
                 Vec3d(normals[3 * v], normals[3 * v + 1], normals[3 * v + 2]));
      g.begin();
      for (std::size_t t = 0; t + 2 < m.indices.size(); t += 3) {
        const std::uint32_t a = m.indices[t], b = m.indices[t + 1], c = m.indices[t + 2];
        if (a < nv && b < nv && c < nv)
          g.indices.insert(g.indices.end(), {base + a, base + b, base + c});
      }
      g.end(Kind::Mesh, GL_TRIANGLES, m.color);
    }
  return g;
}

}  // namespace

struct FluidRenderer::Impl {
  Program sky, surface, floor, sprite_depth, sprite_thickness, sprite_shaded, thickness_blur,
      bilateral, normals, composite, text;
  GLuint empty_vao = 0, mesh_vao = 0, mesh_vbo = 0, mesh_ibo = 0, particle_vao = 0,
         particle_vbo = 0;
  Texture scene_color, scene_depth, fluid_depth, sprite_z, thickness, thickness_tmp, smooth_a,
      smooth_b, normal_tex, text_tex;
  Framebuffer fb_scene, fb_depth, fb_thickness, fb_thickness_tmp, fb_a, fb_b, fb_normals;
  const Framebuffer* smoothed = &fb_depth;
  int width = 0, height = 0;
  Mat4 view, proj;

  Impl() {
    if (epoxy_gl_version() < 33)
      throw std::runtime_error("the OpenGL context is version " +
                               std::to_string(epoxy_gl_version() / 10) + "." +
                               std::to_string(epoxy_gl_version() % 10) + "; 3.3 core is needed");
    using namespace gl;
    sky = Program("sky", source(kFullscreenVs), source(kCommon, kSkyFs));
    surface = Program("surface", source(kSurfaceVs), source(kCommon, kSurfaceFs));
    floor = Program("floor", source(kSurfaceVs), source(kCommon, kFloorFs));
    sprite_depth =
        Program("sprite depth", source(kSpriteVs), source(kSpriteCommon, kSpriteDepthFs));
    sprite_thickness =
        Program("sprite thickness", source(kSpriteVs), source(kSpriteCommon, kSpriteThicknessFs));
    sprite_shaded =
        Program("sprite shaded", source(kSpriteVs), source(kSpriteCommon, kSpriteShadedFs));
    thickness_blur = Program("thickness blur", source(kFullscreenVs), source(kThicknessBlurFs));
    bilateral = Program("bilateral", source(kFullscreenVs), source(kBilateralFs));
    normals = Program("normals", source(kFullscreenVs), source(kCommon, kNormalsFs));
    composite = Program("composite", source(kFullscreenVs), source(kCommon, kCompositeFs));
    text = Program("text", source(kTextVs), source(kTextFs));

    glGenVertexArrays(1, &empty_vao);
    glGenVertexArrays(1, &mesh_vao);
    glGenBuffers(1, &mesh_vbo);
    glGenBuffers(1, &mesh_ibo);
    glBindVertexArray(mesh_vao);
    glBindBuffer(GL_ARRAY_BUFFER, mesh_vbo);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, mesh_ibo);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                          reinterpret_cast<const void*>(3 * sizeof(float)));
    glGenVertexArrays(1, &particle_vao);
    glGenBuffers(1, &particle_vbo);
    glBindVertexArray(particle_vao);
    glBindBuffer(GL_ARRAY_BUFFER, particle_vbo);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 3 * sizeof(float), nullptr);
    glBindVertexArray(0);
  }

  ~Impl() {
    glDeleteBuffers(1, &particle_vbo);
    glDeleteVertexArrays(1, &particle_vao);
    glDeleteBuffers(1, &mesh_ibo);
    glDeleteBuffers(1, &mesh_vbo);
    glDeleteVertexArrays(1, &mesh_vao);
    glDeleteVertexArrays(1, &empty_vao);
  }

  void resize(int w, int h) {
    if (w == width && h == height) return;
    scene_color.allocate(w, h, GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, true);
    scene_depth.allocate(w, h, GL_DEPTH_COMPONENT32F, GL_DEPTH_COMPONENT, GL_FLOAT);
    fluid_depth.allocate(w, h, GL_R32F, GL_RED, GL_FLOAT);
    sprite_z.allocate(w, h, GL_DEPTH_COMPONENT32F, GL_DEPTH_COMPONENT, GL_FLOAT);
    thickness.allocate(w, h, GL_R32F, GL_RED, GL_FLOAT);
    thickness_tmp.allocate(w, h, GL_R32F, GL_RED, GL_FLOAT);
    smooth_a.allocate(w, h, GL_R32F, GL_RED, GL_FLOAT);
    smooth_b.allocate(w, h, GL_R32F, GL_RED, GL_FLOAT);
    normal_tex.allocate(w, h, GL_RGBA32F, GL_RGBA, GL_FLOAT);
    fb_scene.attach("scene", scene_color, &scene_depth);
    fb_depth.attach("fluid depth", fluid_depth, &sprite_z);
    fb_thickness.attach("thickness", thickness, nullptr);
    fb_thickness_tmp.attach("thickness", thickness_tmp, nullptr);
    fb_a.attach("smoothing", smooth_a, nullptr);
    fb_b.attach("smoothing", smooth_b, nullptr);
    fb_normals.attach("normals", normal_tex, nullptr);
    width = w;
    height = h;
  }

  std::vector<float> read(const Framebuffer& fb, int channels) const {
    std::vector<float> raw(std::size_t(width) * height * 4);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, fb.id());
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glReadPixels(0, 0, width, height, GL_RGBA, GL_FLOAT, raw.data());
    // GL rows go bottom to top; the results go top to bottom like Image.
    std::vector<float> out(std::size_t(width) * height * channels);
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x)
        for (int c = 0; c < channels; ++c)
          out[(std::size_t(y) * width + x) * channels + c] =
              raw[(std::size_t(height - 1 - y) * width + x) * 4 + c];
    return out;
  }
};

FluidRenderer::FluidRenderer() : impl_(std::make_unique<Impl>()) {}
FluidRenderer::~FluidRenderer() = default;

void FluidRenderer::render(const RenderFrame& frame, const Camera& cam, const FluidStyle& style,
                           unsigned target) {
  Impl& s = *impl_;
  const int W = std::max(cam.width, 1), H = std::max(cam.height, 1);
  s.resize(W, H);

  Vec3d lo(-0.5, -0.5, -0.5), hi(0.5, 0.5, 0.5);
  frame_bounds(frame, &lo, &hi);
  const double diag = std::max(norm(hi - lo), 1e-6);
  // The floor reaches far enough to meet the horizon, and fades into its colour well before,
  // so that no edge of it shows.
  const double reach = 60 * diag, fade = 4 * diag;
  const ClipRange clip = clip_range(cam, lo, hi, reach);
  s.view = view_matrix(cam);
  s.proj = projection_matrix(cam, clip.near, clip.far);
  const auto view_f = s.view.to_float(), proj_f = s.proj.to_float();
  const auto inv_view_f = inverse_rigid(s.view).to_float();
  const float focal = float(0.5 * H * s.proj(1, 1));  // pixels per unit of x / depth
  const Vec3d light = style.light_dir / std::max(norm(style.light_dir), 1e-12);
  const Vec3d light_eye = transform(s.view, light, 0.0);
  const float radius = std::max(frame.radius, 1e-9f);

  auto camera_uniforms = [&](const Program& p) {
    p.use();
    p.set("uViewport", float(W), float(H));
    p.set("uProjScale", float(s.proj(0, 0)), float(s.proj(1, 1)));
    p.set("uInvView", inv_view_f);
    p.set("uView", view_f);
    p.set("uProj", proj_f);
    p.set("uSkyZenith", kSkyZenith);
    p.set("uSkyHorizon", kSkyHorizon);
    p.set("uGround", kGround);
    p.set("uLightEye", light_eye);
    p.set("uRadius", radius);
    p.set("uFocal", focal);
  };
  auto fullscreen = [&] {
    glBindVertexArray(s.empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
  };

  // Uploads: opaque geometry, and the particles (non-finite ones left out).
  const Geometry g = build_geometry(frame, style, cam, lo, hi, reach);
  glBindVertexArray(s.mesh_vao);
  glBindBuffer(GL_ARRAY_BUFFER, s.mesh_vbo);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(g.vertices.size() * sizeof(float)), g.vertices.data(),
               GL_STREAM_DRAW);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(g.indices.size() * sizeof(std::uint32_t)),
               g.indices.data(), GL_STREAM_DRAW);
  std::vector<float> particles;
  particles.reserve(frame.particles.size());
  for (std::size_t i = 0; i + 2 < frame.particles.size(); i += 3)
    if (std::isfinite(frame.particles[i] + frame.particles[i + 1] + frame.particles[i + 2]))
      particles.insert(particles.end(), frame.particles.begin() + std::ptrdiff_t(i),
                       frame.particles.begin() + std::ptrdiff_t(i + 3));
  const GLsizei n = GLsizei(particles.size() / 3);
  glBindBuffer(GL_ARRAY_BUFFER, s.particle_vbo);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(particles.size() * sizeof(float)), particles.data(),
               GL_STREAM_DRAW);
  glEnable(GL_PROGRAM_POINT_SIZE);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);

  // Scene: sky, then floor, walls, bodies and edges with depth.
  glBindFramebuffer(GL_FRAMEBUFFER, s.fb_scene.id());
  glViewport(0, 0, W, H);
  glClearColor(0, 0, 0, 1);
  glClearDepth(1.0);
  glDepthMask(GL_TRUE);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glDisable(GL_DEPTH_TEST);
  glDepthMask(GL_FALSE);
  camera_uniforms(s.sky);
  fullscreen();
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glBindVertexArray(s.mesh_vao);
  const double box_extent = std::max(hi.x - lo.x, hi.z - lo.z);
  for (const Geometry::Draw& d : g.draws) {
    const void* first = reinterpret_cast<const void*>(d.first * sizeof(std::uint32_t));
    if (d.kind == Kind::Floor) {
      camera_uniforms(s.floor);
      s.floor.set("uColor", d.color);
      s.floor.set("uGrid", float(grid_spacing(box_extent)));
      s.floor.set("uReach", float(fade));
      s.floor.set("uCenter", float(0.5 * (lo.x + hi.x)), float(0.5 * (lo.z + hi.z)));
      // Pushed back so that the tank's bottom edges, drawn on it, win the depth test.
      glEnable(GL_POLYGON_OFFSET_FILL);
      glPolygonOffset(1.0f, 1.0f);
      glDrawElements(d.mode, GLsizei(d.count), GL_UNSIGNED_INT, first);
      glDisable(GL_POLYGON_OFFSET_FILL);
      continue;
    }
    camera_uniforms(s.surface);
    s.surface.set("uLit", d.kind == Kind::Edge ? 0 : d.kind == Kind::Wall ? 2 : 1);
    s.surface.set("uSpecular", 0.25f);
    s.surface.set("uColor", d.color);
    if (d.kind == Kind::Wall) {
      // Pushed back like the floor: the edges lie in the walls' planes.
      glEnable(GL_POLYGON_OFFSET_FILL);
      glPolygonOffset(1.0f, 1.0f);
      glDrawElements(d.mode, GLsizei(d.count), GL_UNSIGNED_INT, first);
      glDisable(GL_POLYGON_OFFSET_FILL);
      continue;
    }
    if (d.kind == Kind::Edge) {
      glDrawElements(d.mode, GLsizei(d.count), GL_UNSIGNED_INT, first);
      continue;
    }
    if (style.meshes) {
      // Pushed back a little so that the wireframe on top wins the depth test.
      glEnable(GL_POLYGON_OFFSET_FILL);
      glPolygonOffset(1.0f, 1.0f);
      glDrawElements(d.mode, GLsizei(d.count), GL_UNSIGNED_INT, first);
      glDisable(GL_POLYGON_OFFSET_FILL);
    }
    if (style.wireframe) {
      s.surface.set("uLit", 0);
      s.surface.set("uColor", style.meshes ? kWireColor : d.color);
      glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
      glDrawElements(d.mode, GLsizei(d.count), GL_UNSIGNED_INT, first);
      glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    }
  }
  const bool spheres = style.particles && n > 0;
  if (spheres) {
    camera_uniforms(s.sprite_shaded);
    s.sprite_shaded.set("uColor", kParticleColor);
    glBindVertexArray(s.particle_vao);
    glDrawArrays(GL_POINTS, 0, n);
  }
  const bool surface = style.surface && !style.particles && n > 0;

  // Depth: nearest sphere surface per pixel, hidden parts of the water left out.
  glBindFramebuffer(GL_FRAMEBUFFER, s.fb_depth.id());
  glClearColor(0, 0, 0, 0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  if (surface) {
    camera_uniforms(s.sprite_depth);
    s.scene_depth.bind(0);
    s.sprite_depth.set("uSceneDepth", 0);
    glBindVertexArray(s.particle_vao);
    glDrawArrays(GL_POINTS, 0, n);
  }
  glDisable(GL_DEPTH_TEST);
  glDepthMask(GL_FALSE);

  // Thickness: every sphere's chord along the view ray, summed.
  glBindFramebuffer(GL_FRAMEBUFFER, s.fb_thickness.id());
  glClear(GL_COLOR_BUFFER_BIT);
  if (surface) {
    glEnable(GL_BLEND);
    glBlendEquation(GL_FUNC_ADD);
    glBlendFunc(GL_ONE, GL_ONE);
    camera_uniforms(s.sprite_thickness);
    s.scene_depth.bind(0);
    s.sprite_thickness.set("uSceneDepth", 0);
    glBindVertexArray(s.particle_vao);
    glDrawArrays(GL_POINTS, 0, n);
    glDisable(GL_BLEND);
    s.thickness_blur.use();
    s.thickness_blur.set("uThickness", 0);
    s.thickness_blur.set("uDepth", 1);
    s.thickness_blur.set("uWorldRadius", float(2.0 * radius));
    s.thickness_blur.set("uFocal", focal);
    s.thickness_blur.set("uMaxPx", float(std::max(style.smoothing_max_px, 1.0)));
    s.fluid_depth.bind(1);
    for (int pass = 0; pass < 2; ++pass) {
      glBindFramebuffer(GL_FRAMEBUFFER, (pass == 0 ? s.fb_thickness_tmp : s.fb_thickness).id());
      (pass == 0 ? s.thickness : s.thickness_tmp).bind(0);
      s.thickness_blur.set("uDir", pass == 0 ? 1 : 0, pass == 0 ? 0 : 1);
      fullscreen();
    }
  }

  // Smoothing: horizontal then vertical bilateral sweeps, ping-pong between two targets.
  const Texture* depth = &s.fluid_depth;
  s.smoothed = &s.fb_depth;
  if (surface) {
    s.bilateral.use();
    s.bilateral.set("uDepth", 0);
    s.bilateral.set("uWorldRadius", float(style.smoothing_radius * radius));
    s.bilateral.set("uFocal", focal);
    s.bilateral.set("uMaxPx", float(std::max(style.smoothing_max_px, 1.0)));
    // Depth steps up to about a particle diameter are bumps of one surface; larger ones
    // separate layers.
    s.bilateral.set("uRangeSigma", 2.0f * radius);
    for (int it = 0; it < style.smoothing_iterations; ++it) {
      for (int pass = 0; pass < 2; ++pass) {
        const Framebuffer& out = pass == 0 ? s.fb_a : s.fb_b;
        glBindFramebuffer(GL_FRAMEBUFFER, out.id());
        depth->bind(0);
        s.bilateral.set("uDir", pass == 0 ? 1 : 0, pass == 0 ? 0 : 1);
        fullscreen();
        depth = pass == 0 ? &s.smooth_a : &s.smooth_b;
        s.smoothed = &out;
      }
    }
  }

  // Normals from the smoothed depth.
  glBindFramebuffer(GL_FRAMEBUFFER, s.fb_normals.id());
  glClear(GL_COLOR_BUFFER_BIT);
  if (surface) {
    camera_uniforms(s.normals);
    depth->bind(0);
    s.normals.set("uDepth", 0);
    fullscreen();
  }

  // Composite: the water over the scene, into the caller's framebuffer.
  glBindFramebuffer(GL_FRAMEBUFFER, target);
  glViewport(0, 0, W, H);
  Vec3d absorb = style.absorption;
  if (!(absorb.x > 0 || absorb.y > 0 || absorb.z > 0)) {
    // Red goes first, blue last: a quarter of the tank's height looks deep blue.
    const double depth_scale = std::max(0.25 * (hi.y - lo.y), 4.0 * radius);
    absorb = Vec3d(1.6, 0.6, 0.24) / depth_scale;
  }
  camera_uniforms(s.composite);
  s.composite.set("uAbsorb", absorb);
  s.composite.set("uWaterColor", kWaterBody);
  s.composite.set("uRefract", float(style.refraction));
  s.scene_color.bind(0);
  s.scene_depth.bind(1);
  s.normal_tex.bind(2);
  s.thickness.bind(3);
  s.composite.set("uScene", 0);
  s.composite.set("uSceneDepth", 1);
  s.composite.set("uNormal", 2);
  s.composite.set("uThickness", 3);
  fullscreen();
  glBindVertexArray(0);
  glActiveTexture(GL_TEXTURE0);
}

void FluidRenderer::draw_text(const std::string& text, int x, int y, int scale, unsigned target,
                              int width, int height) {
  Impl& s = *impl_;
  if (text.empty() || width <= 0 || height <= 0) return;
  const TextMask m = rasterize_text(text, scale);
  s.text_tex.allocate(m.width, m.height, GL_R8, GL_RED, GL_UNSIGNED_BYTE, false);
  s.text_tex.bind(0);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, m.width, m.height, GL_RED, GL_UNSIGNED_BYTE,
                  m.alpha.data());
  glBindFramebuffer(GL_FRAMEBUFFER, target);
  glViewport(0, 0, width, height);
  glDisable(GL_DEPTH_TEST);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  auto ndc_x = [&](double px) { return float(px / width * 2 - 1); };
  auto ndc_y = [&](double py) { return float(1 - py / height * 2); };
  s.text.use();
  s.text.set("uMask", 0);
  glBindVertexArray(s.empty_vao);
  s.text.set("uSolid", 1);
  s.text.set("uColor", 0.0f, 0.0f, 0.0f, 0.45f);
  s.text.set("uRect", ndc_x(x), ndc_y(y + m.height), ndc_x(x + m.width), ndc_y(y));
  glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
  s.text.set("uSolid", 0);
  s.text.set("uColor", 1.0f, 1.0f, 1.0f, 1.0f);
  glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
  glDisable(GL_BLEND);
  glBindVertexArray(0);
}

std::vector<float> FluidRenderer::fluid_depth() const { return impl_->read(impl_->fb_depth, 1); }
std::vector<float> FluidRenderer::smoothed_depth() const {
  return impl_->read(*impl_->smoothed, 1);
}
std::vector<float> FluidRenderer::normals() const { return impl_->read(impl_->fb_normals, 3); }
std::vector<float> FluidRenderer::thickness() const { return impl_->read(impl_->fb_thickness, 1); }
const Mat4& FluidRenderer::view() const { return impl_->view; }
const Mat4& FluidRenderer::projection() const { return impl_->proj; }

std::string FluidRenderer::device() const {
  auto str = [](GLenum e) {
    const GLubyte* s = glGetString(e);
    return s ? std::string(reinterpret_cast<const char*>(s)) : std::string("?");
  };
  return str(GL_RENDERER) + ", " + str(GL_VERSION);
}

}  // namespace sphfem::render
