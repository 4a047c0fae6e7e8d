#include "sphfem/render/splat.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

namespace sphfem::render {
namespace {

struct Rgb {
  double r, g, b;
};

Rgb mix(const Rgb& a, const Rgb& b, double t) {
  return {a.r + (b.r - a.r) * t, a.g + (b.g - a.g) * t, a.b + (b.b - a.b) * t};
}
Rgb scale(const Rgb& a, double s) { return {a.r * s, a.g * s, a.b * s}; }
// NaN (e.g. from a corrupt speed) maps to 0 rather than to an undefined byte.
double clamp01(double v) { return v > 0 ? (v < 1 ? v : 1) : 0; }
double smooth01(double v) {
  v = clamp01(v);
  return v * v * (3 - 2 * v);
}
std::uint8_t to8(double v) { return std::uint8_t(std::lround(clamp01(v) * 255.0)); }

// Palette: light neutral surroundings so that blue means water and nothing else.
const Rgb kSkyTop{0.84, 0.87, 0.91}, kSkyBottom{0.96, 0.96, 0.97};
const Rgb kFloor{0.80, 0.80, 0.79}, kWall{0.90, 0.90, 0.91};
const Rgb kShallow{0.30, 0.64, 0.92}, kDeep{0.03, 0.20, 0.46};
const Rgb kFoam{0.94, 0.97, 1.0}, kRimSky{0.82, 0.90, 1.0};
const Rgb kEdge{0.16, 0.18, 0.22};

// One particle after projection: view-space centre and the pixel rectangle it may cover.
struct Splat {
  float x, y, z;
  int x0, x1, y0, y1;  // inclusive; x0 > x1 when nothing is drawn
};

// Exact extent of a sphere's image along one screen axis: the two planes through the eye
// that touch the sphere, as slopes (coordinate / depth).
bool tangent_slopes(double c, double z, double r, double* lo, double* hi) {
  const double a = z * z - r * r;
  const double disc = c * c + a;  // c^2 + z^2 - r^2
  if (a <= 0 || disc <= 0) return false;
  const double s = r * std::sqrt(disc);
  *lo = (c * z - s) / a;
  *hi = (c * z + s) / a;
  return true;
}

// Cell of coordinate `u` (in cells), limited to [-1, n] before conversion so that far-away
// points cannot overflow an int; NaN goes to -1.
int index(double u, int n) { return u >= -1 ? int(std::floor(std::min(u, double(n)))) : -1; }

// Top of the water over the box floor, on a grid of cells about a particle radius wide:
// depth below it darkens the water and shades the floor, like light absorbed from above.
struct WaterTop {
  double x0 = 0, z0 = 0, cell = 1;
  int nx = 0, nz = 0;
  std::vector<float> top;    // -inf where no water
  std::vector<float> shade;  // 0..1, how much water shades the floor; blurred for soft edges

  float at(double x, double z) const {
    const int i = index((x - x0) / cell, nx), k = index((z - z0) / cell, nz);
    if (i < 0 || k < 0 || i >= nx || k >= nz) return -std::numeric_limits<float>::infinity();
    return top[std::size_t(k) * nx + i];
  }
  // Bilinear between cell centres, so shadow edges do not show the cells.
  double shadow(double x, double z) const {
    const double u = std::clamp((x - x0) / cell - 0.5, -1.0, double(nx)),
                 v = std::clamp((z - z0) / cell - 0.5, -1.0, double(nz));
    const int i = int(std::floor(u)), k = int(std::floor(v));
    const double fu = u - i, fv = v - k;
    auto s = [&](int a, int b) {
      a = std::clamp(a, 0, nx - 1);
      b = std::clamp(b, 0, nz - 1);
      return double(shade[std::size_t(b) * nx + a]);
    };
    return (s(i, k) * (1 - fu) + s(i + 1, k) * fu) * (1 - fv) +
           (s(i, k + 1) * (1 - fu) + s(i + 1, k + 1) * fu) * fv;
  }
};

// Box blur of `reach` cells each way along x, then along z.
void blur(std::vector<float>& m, int nx, int nz, int reach) {
  std::vector<float> tmp(m.size());
  for (int pass = 0; pass < 2; ++pass) {
    const int n = pass == 0 ? nx : nz, lines = pass == 0 ? nz : nx;
    const std::size_t step = pass == 0 ? 1 : std::size_t(nx);
    for (int l = 0; l < lines; ++l) {
      const std::size_t base = pass == 0 ? std::size_t(l) * nx : std::size_t(l);
      for (int a = 0; a < n; ++a) {
        double sum = 0;
        for (int b = a - reach; b <= a + reach; ++b)
          sum += b >= 0 && b < n ? m[base + b * step] : 0;
        tmp[base + a * step] = float(sum / (2 * reach + 1));
      }
    }
    m.swap(tmp);
  }
}

WaterTop water_top(const std::vector<float>& pos, float radius, const Vec3d& lo, const Vec3d& hi,
                   double absorb) {
  WaterTop w;
  const double ex = std::max(hi.x - lo.x, 1e-9), ez = std::max(hi.z - lo.z, 1e-9);
  w.cell = std::max({double(radius), ex / 1024, ez / 1024});
  w.x0 = lo.x;
  w.z0 = lo.z;
  w.nx = std::max(1, int(std::ceil(ex / w.cell)));
  w.nz = std::max(1, int(std::ceil(ez / w.cell)));
  w.top.assign(std::size_t(w.nx) * w.nz, -std::numeric_limits<float>::infinity());
  const std::size_t n = pos.size() / 3;
  // A max over particles: the same result in any order.
  for (std::size_t p = 0; p < n; ++p) {
    const double x = pos[3 * p], y = pos[3 * p + 1], z = pos[3 * p + 2];
    if (!std::isfinite(x + y + z)) continue;
    const int i0 = std::max(0, index((x - radius - w.x0) / w.cell, w.nx));
    const int i1 = std::min(w.nx - 1, index((x + radius - w.x0) / w.cell, w.nx));
    const int k0 = std::max(0, index((z - radius - w.z0) / w.cell, w.nz));
    const int k1 = std::min(w.nz - 1, index((z + radius - w.z0) / w.cell, w.nz));
    const float t = float(y + radius);
    for (int k = k0; k <= k1; ++k)
      for (int i = i0; i <= i1; ++i) {
        float& v = w.top[std::size_t(k) * w.nx + i];
        v = std::max(v, t);
      }
  }
  w.shade.resize(w.top.size());
  for (std::size_t c = 0; c < w.top.size(); ++c)
    w.shade[c] = w.top[c] > lo.y ? float(1 - std::exp(-(w.top[c] - lo.y) / absorb)) : 0.0f;
  for (int pass = 0; pass < 2; ++pass) blur(w.shade, w.nx, w.nz, 2);
  return w;
}

// Spacing of the floor grid: the largest of 1, 2, 5 x 10^k giving at least six cells.
double grid_spacing(double extent) {
  if (!(extent > 0)) return 1;
  const double base = std::pow(10.0, std::floor(std::log10(extent)));
  for (double g : {base, base / 2, base / 5, base / 10, base / 20, base / 50})
    if (extent / g >= 6) return g;
  return base / 100;
}

// Coverage of thin grid lines every `g` at coordinate `u`, for a pixel `fp` wide on the floor.
double grid_line(double u, double g, double fp) {
  const double f = (u / g) - std::floor(u / g);
  const double d = std::min(f, 1 - f) * g;
  return clamp01(1 - d / std::max(fp, 1e-12));
}

// The picture at the camera's own resolution; `px_scale` of its pixels make one output pixel,
// so lines and the grid keep their width when supersampled.
Image draw(const Camera& camera, const std::vector<float>& positions_xyz,
           const std::vector<float>* speed, float radius, const Vec3d& lo, const Vec3d& hi,
           const RenderStyle& style, int px_scale) {
  const std::size_t n = positions_xyz.size() / 3;
  const int W = camera.width, H = camera.height;
  const ViewFrame vf(camera);
  const float f = float(vf.focal), cx = float(vf.cx), cy = float(vf.cy);
  const float r = radius, r2 = radius * radius;

  // 1. Project every particle to a screen rectangle (independent per particle).
  std::vector<Splat> splats(n);
#pragma omp parallel for schedule(static)
  for (long long p = 0; p < (long long)n; ++p) {
    const Vec3d c =
        vf.to_view(Vec3d(positions_xyz[3 * p], positions_xyz[3 * p + 1], positions_xyz[3 * p + 2]));
    Splat& s = splats[p];
    s = {float(c.x), float(c.y), float(c.z), 0, -1, 0, -1};
    double sx0, sx1, sy0, sy1;
    if (!std::isfinite(c.x + c.y + c.z) || c.z <= radius ||
        !tangent_slopes(c.x, c.z, radius, &sx0, &sx1) ||
        !tangent_slopes(c.y, c.z, radius, &sy0, &sy1))
      continue;
    // Pixels whose centres (i + 0.5) lie inside the image of the sphere.
    const double px0 = vf.cx + vf.focal * sx0, px1 = vf.cx + vf.focal * sx1;
    const double py0 = vf.cy - vf.focal * sy1, py1 = vf.cy - vf.focal * sy0;
    if (px1 < -1 || py1 < -1 || px0 > W + 1 || py0 > H + 1) continue;
    // Clamped before conversion: a sphere just in front of the eye covers a huge range.
    s.x0 = int(std::ceil(std::max(px0, -2.0) - 0.5)) - 1;
    s.x1 = int(std::floor(std::min(px1, W + 2.0) - 0.5)) + 1;
    s.y0 = int(std::ceil(std::max(py0, -2.0) - 0.5)) - 1;
    s.y1 = int(std::floor(std::min(py1, H + 2.0) - 0.5)) + 1;
    s.x0 = std::max(s.x0, 0), s.x1 = std::min(s.x1, W - 1);
    s.y0 = std::max(s.y0, 0), s.y1 = std::min(s.y1, H - 1);
  }

  // 2. Bin splats by bands of rows; each band is then drawn by one thread alone.
  constexpr int kBand = 8;
  const int bands = (H + kBand - 1) / kBand;
  std::vector<std::size_t> start(std::size_t(bands) + 1, 0);
  for (const Splat& s : splats)
    if (s.x0 <= s.x1 && s.y0 <= s.y1)
      for (int b = s.y0 / kBand; b <= s.y1 / kBand; ++b) ++start[b + 1];
  for (int b = 0; b < bands; ++b) start[b + 1] += start[b];
  std::vector<std::uint32_t> binned(start[bands]);
  {
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (std::size_t p = 0; p < n; ++p) {
      const Splat& s = splats[p];
      if (s.x0 <= s.x1 && s.y0 <= s.y1)
        for (int b = s.y0 / kBand; b <= s.y1 / kBand; ++b) binned[fill[b]++] = std::uint32_t(p);
    }
  }

  // Ray of pixel (i, j) in view space is (ax[i], by[j], 1): its parameter is the depth.
  std::vector<float> ax(W), by(H);
  for (int i = 0; i < W; ++i) ax[i] = (float(i) + 0.5f - cx) / f;
  for (int j = 0; j < H; ++j) by[j] = -(float(j) + 0.5f - cy) / f;

  // 3. Nearest sphere per pixel. Ties go to the lower particle index, so the result is
  // a pure minimum and does not depend on drawing order.
  const std::size_t npix = std::size_t(W) * H;
  std::vector<float> zbuf(npix, std::numeric_limits<float>::infinity());
  std::vector<std::int32_t> owner(npix, -1);
#pragma omp parallel for schedule(dynamic, 1)
  for (int b = 0; b < bands; ++b) {
    const int row0 = b * kBand, row1 = std::min(H, row0 + kBand) - 1;
    for (std::size_t k = start[b]; k < start[b + 1]; ++k) {
      const std::uint32_t p = binned[k];
      const Splat& s = splats[p];
      for (int j = std::max(s.y0, row0); j <= std::min(s.y1, row1); ++j) {
        const float b_ = by[j];
        float* zrow = zbuf.data() + std::size_t(j) * W;
        std::int32_t* orow = owner.data() + std::size_t(j) * W;
        for (int i = s.x0; i <= s.x1; ++i) {
          const float a = ax[i];
          const float dd = a * a + b_ * b_ + 1.0f;
          const float tc = (a * s.x + b_ * s.y + s.z) / dd;  // closest approach to the centre
          const float qx = s.x - tc * a, qy = s.y - tc * b_, qz = s.z - tc;
          const float miss2 = qx * qx + qy * qy + qz * qz;
          if (miss2 > r2) continue;
          const float t = tc - std::sqrt((r2 - miss2) / dd);
          if (t < zrow[i] || (t == zrow[i] && std::int32_t(p) < orow[i])) {
            zrow[i] = t;
            orow[i] = std::int32_t(p);
          }
        }
      }
    }
  }

  // 4. Shade each pixel on its own: sky, tank surfaces, water.
  const double absorb =
      style.absorption_length > 0 ? style.absorption_length : std::max(0.25 * (hi.y - lo.y), 1e-6);
  const WaterTop wtop = water_top(positions_xyz, radius, lo, hi, absorb);
  const double grid = grid_spacing(std::max(hi.x - lo.x, hi.z - lo.z));
  const Vec3d light = Vec3d(-0.35, 0.85, 0.40) / norm(Vec3d(-0.35, 0.85, 0.40));
  const double foam_span = std::max(style.foam_full - style.foam_start, 1e-9);
  Image img(W, H);
  std::vector<float> scene_depth(npix, std::numeric_limits<float>::infinity());

#pragma omp parallel for schedule(static)
  for (int j = 0; j < H; ++j) {
    const Rgb sky = mix(kSkyTop, kSkyBottom, smooth01((j + 0.5) / H));
    for (int i = 0; i < W; ++i) {
      const std::size_t pix = std::size_t(j) * W + i;
      const Vec3d d = vf.ray(i + 0.5, j + 0.5);
      const double dlen = norm(d);
      Rgb c = sky;
      double depth = std::numeric_limits<double>::infinity();

      // The far side of the box: where a ray leaves it is floor or wall (the top is open).
      double tn = -std::numeric_limits<double>::infinity(), tf = -tn;
      int exit_axis = -1, exit_side = 0;
      for (int a = 0; a < 3; ++a) {
        const double o = vf.eye[a], v = d[a];
        if (std::fabs(v) < 1e-300) {
          if (o < lo[a] || o > hi[a]) tf = -1;
          continue;
        }
        double t0 = (lo[a] - o) / v, t1 = (hi[a] - o) / v;
        int side1 = 1;
        if (t0 > t1) {
          std::swap(t0, t1);
          side1 = 0;
        }
        tn = std::max(tn, t0);
        if (t1 < tf) {
          tf = t1;
          exit_axis = a;
          exit_side = side1;
        }
      }
      const bool hits_box = exit_axis >= 0 && tf > 0 && tf >= tn;
      const bool on_floor = hits_box && exit_axis == 1 && exit_side == 0 && style.floor;
      const bool on_wall = hits_box && exit_axis != 1 && style.walls;
      if (on_floor || on_wall) {
        const Vec3d pt = vf.eye + d * tf;
        const double fp = px_scale * tf * dlen / vf.focal;  // world size of a pixel, face-on
        if (on_floor) {
          const double slant = std::max(std::fabs(d.y) / dlen, 0.15);
          const double line = std::max(grid_line(pt.x - lo.x, grid, fp / slant),
                                       grid_line(pt.z - lo.z, grid, fp / slant));
          c = scale(kFloor, 1 - 0.10 * line);
          // Water above the floor shades it; the shadow is grey so it never reads as water.
          c = scale(c, 1 - 0.3 * wtop.shadow(pt.x, pt.z));
        } else {
          // Side walls a shade darker than the back one, and both darker towards the floor.
          const double face = exit_axis == 2 ? 1.0 : 0.94;
          const double h = clamp01((pt.y - lo.y) / std::max(hi.y - lo.y, 1e-12));
          c = scale(kWall, face * (0.90 + 0.10 * h));
        }
        depth = tf;
      }

      const std::int32_t p = owner[pix];
      if (p >= 0 && zbuf[pix] < depth) {
        const Splat& s = splats[p];
        const double t = zbuf[pix];
        const double a = ax[i], b = by[j];
        // Normal of the sphere at the hit, from view space to world.
        const Vec3d nv((t * a - s.x) / r, (t * b - s.y) / r, (t - s.z) / r);
        Vec3d nrm = vf.right * nv.x + vf.up * nv.y + vf.forward * nv.z;
        nrm = nrm / std::max(norm(nrm), 1e-12);
        const Vec3d view = -d / dlen;
        const Vec3d pt = vf.eye + d * t;
        const double below = std::max(0.0, double(wtop.at(pt.x, pt.z)) - pt.y);
        Rgb water = mix(kShallow, kDeep, 1 - std::exp(-below / absorb));
        if (speed)
          water = mix(water, kFoam, 0.8 * clamp01(((*speed)[p] - style.foam_start) / foam_span));
        const double ndl = std::max(0.0, dot(nrm, light));
        const double ndv = clamp01(dot(nrm, view));
        Vec3d half = light + view;
        half = half / std::max(norm(half), 1e-12);
        const double spec = style.specular * std::pow(std::max(0.0, dot(nrm, half)), 48.0);
        const double fresnel = 0.04 + 0.31 * std::pow(1 - ndv, 4.0);
        c = scale(water, 0.55 + 0.45 * ndl);
        c = mix(c, kRimSky, fresnel);
        c = mix(c, Rgb{1, 1, 1}, clamp01(spec));
        depth = t;
      }
      std::uint8_t* px = img.at(i, j);
      px[0] = to8(c.r);
      px[1] = to8(c.g);
      px[2] = to8(c.b);
      scene_depth[pix] = float(depth);
    }
  }

  if (!style.edges) return img;

  // 5. The 12 box edges, anti-aliased, depth-tested against what was drawn: edges behind the
  // water stay faintly visible, as through glass. Coverage is a max, so order is irrelevant.
  std::vector<float> seen(npix, 0.0f), hidden(npix, 0.0f);
  const double near = 1e-6 * std::max(norm(hi - lo), 1e-9);
  const double half_width = 0.6 * px_scale;  // pixels
  for (int e = 0; e < 12; ++e) {
    const int axis = e / 4, o1 = (axis + 1) % 3, o2 = (axis + 2) % 3;
    Vec3d wa = lo, wb = lo;
    wa[o1] = wb[o1] = (e & 1) ? hi[o1] : lo[o1];
    wa[o2] = wb[o2] = (e & 2) ? hi[o2] : lo[o2];
    wb[axis] = hi[axis];
    Vec3d va = vf.to_view(wa), vb = vf.to_view(wb);
    if (va.z < near && vb.z < near) continue;
    // Clip at the near plane so both ends project.
    if (va.z < near) va = vb + (va - vb) * ((vb.z - near) / (vb.z - va.z));
    if (vb.z < near) vb = va + (vb - va) * ((va.z - near) / (va.z - vb.z));
    const double x0 = vf.cx + vf.focal * va.x / va.z, y0 = vf.cy - vf.focal * va.y / va.z;
    const double x1 = vf.cx + vf.focal * vb.x / vb.z, y1 = vf.cy - vf.focal * vb.y / vb.z;
    const double dx = x1 - x0, dy = y1 - y0, len2 = dx * dx + dy * dy;
    // Walk only the part of the segment near the image (Liang-Barsky clipping).
    double u0 = 0, u1 = 1;
    const double m = 4.0 * px_scale;
    const double pq[4][2] = {{-dx, x0 + m}, {dx, W + m - x0}, {-dy, y0 + m}, {dy, H + m - y0}};
    for (const auto& c : pq) {
      if (c[0] == 0) {
        if (c[1] < 0) u1 = -1;
      } else if (c[0] < 0) {
        u0 = std::max(u0, c[1] / c[0]);
      } else {
        u1 = std::min(u1, c[1] / c[0]);
      }
    }
    if (u0 > u1) continue;
    const int steps = int(std::ceil(2 * (u1 - u0) * std::sqrt(len2))) + 1;
    const int reach = 1 + int(std::ceil(half_width + 0.5 * px_scale));
    for (int k = 0; k <= steps; ++k) {
      const double u = u0 + (u1 - u0) * k / steps;
      const int ci = int(std::floor(x0 + u * dx)), cj = int(std::floor(y0 + u * dy));
      for (int j = cj - reach; j <= cj + reach; ++j) {
        if (j < 0 || j >= H) continue;
        for (int i = ci - reach; i <= ci + reach; ++i) {
          if (i < 0 || i >= W) continue;
          const double px = i + 0.5 - x0, py = j + 0.5 - y0;
          const double s = len2 > 0 ? clamp01((px * dx + py * dy) / len2) : 0;
          const double ex = px - s * dx, ey = py - s * dy;
          const float cov = float(
              clamp01((half_width + 0.5 * px_scale - std::sqrt(ex * ex + ey * ey)) / px_scale));
          if (cov <= 0) continue;
          // Depth is linear in 1/z along the screen segment.
          const double z = 1.0 / ((1 - s) / va.z + s / vb.z);
          const std::size_t pix = std::size_t(j) * W + i;
          float& slot = z <= scene_depth[pix] * (1 + 2e-3) ? seen[pix] : hidden[pix];
          slot = std::max(slot, cov);
        }
      }
    }
  }
#pragma omp parallel for schedule(static)
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < W; ++i) {
      const std::size_t pix = std::size_t(j) * W + i;
      const double alpha = std::max(0.85 * seen[pix], 0.30 * hidden[pix]);
      if (alpha <= 0) continue;
      std::uint8_t* px = img.at(i, j);
      px[0] = to8((px[0] / 255.0) * (1 - alpha) + kEdge.r * alpha);
      px[1] = to8((px[1] / 255.0) * (1 - alpha) + kEdge.g * alpha);
      px[2] = to8((px[2] / 255.0) * (1 - alpha) + kEdge.b * alpha);
    }
  return img;
}

}  // namespace

Image render_particles(const Camera& camera, const std::vector<float>& positions_xyz,
                       const std::vector<float>* speed, float radius, const Vec3d& box_lo,
                       const Vec3d& box_hi, const RenderStyle& style) {
  if (camera.width <= 0 || camera.height <= 0)
    throw std::invalid_argument("render_particles: the camera has an empty image size");
  if (positions_xyz.size() % 3 != 0)
    throw std::invalid_argument("render_particles: positions must hold 3 floats per particle");
  const std::size_t n = positions_xyz.size() / 3;
  if (speed && speed->size() != n)
    throw std::invalid_argument("render_particles: speed must hold one value per particle");
  if (n > 0 && !(radius > 0)) throw std::invalid_argument("render_particles: radius must be > 0");
  const Vec3d lo = vmin(box_lo, box_hi), hi = vmax(box_lo, box_hi);
  const int ss = std::clamp(style.supersample, 1, 4);
  if (ss == 1) return draw(camera, positions_xyz, speed, radius, lo, hi, style, 1);

  // Draw ss x ss samples per pixel and average them in integers, which keeps the result exact.
  Camera big = camera;
  big.width *= ss;
  big.height *= ss;
  const Image fine = draw(big, positions_xyz, speed, radius, lo, hi, style, ss);
  Image img(camera.width, camera.height);
  const int count = ss * ss;
#pragma omp parallel for schedule(static)
  for (int j = 0; j < img.height; ++j)
    for (int i = 0; i < img.width; ++i)
      for (int ch = 0; ch < 3; ++ch) {
        int sum = 0;
        for (int b = 0; b < ss; ++b)
          for (int a = 0; a < ss; ++a) sum += fine.at(i * ss + a, j * ss + b)[ch];
        img.at(i, j)[ch] = std::uint8_t((sum + count / 2) / count);
      }
  return img;
}

}  // namespace sphfem::render
