// GLSL 3.30 core sources of the renderer's passes (see fluid_gl.h for the pipeline). Each
// program is kVersion + kCommon (where it needs the camera helpers) + its own text.
#pragma once

namespace sphfem::render::gl {

inline constexpr const char* kVersion = "#version 330 core\n";

// Camera helpers shared by the fragment shaders that work in eye space or shade with the sky.
inline constexpr const char* kCommon = R"(
uniform vec2 uViewport;   // pixels
uniform vec2 uProjScale;  // projection matrix entries [0][0] and [1][1]
uniform mat4 uInvView;
uniform vec3 uSkyZenith, uSkyHorizon, uGround;

// Eye-space point at window position `frag` (pixels) and positive eye depth `depth`.
vec3 eye_position(vec2 frag, float depth) {
  vec2 ndc = frag / uViewport * 2.0 - 1.0;
  return vec3(ndc * depth / uProjScale, -depth);
}

// The environment: a sky gradient above the horizon, a plain ground below it.
vec3 sky(vec3 d) {
  float t = clamp(d.y, -1.0, 1.0);
  if (t >= 0.0) return mix(uSkyHorizon, uSkyZenith, pow(t, 0.7));
  return mix(uSkyHorizon, uGround, smoothstep(0.0, 0.5, -t));
}
)";

// A triangle covering the viewport, with no vertex buffer.
inline constexpr const char* kFullscreenVs = R"(
void main() {
  vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
)";

inline constexpr const char* kSkyFs = R"(
out vec4 oColor;
void main() {
  vec3 d = normalize(vec3((gl_FragCoord.xy / uViewport * 2.0 - 1.0) / uProjScale, -1.0));
  oColor = vec4(sky(normalize(mat3(uInvView) * d)), 1.0);
}
)";

// Triangles and lines in world space with a normal: bodies, tank walls, floor, edges.
inline constexpr const char* kSurfaceVs = R"(
layout(location = 0) in vec3 aPos;
layout(location = 1) in vec3 aNormal;
uniform mat4 uView, uProj;
out vec3 vEye, vNormal, vWorld;
void main() {
  vec4 e = uView * vec4(aPos, 1.0);
  vEye = e.xyz;
  vWorld = aPos;
  vNormal = mat3(uView) * aNormal;
  gl_Position = uProj * e;
}
)";

// uLit 1: Blinn-Phong with a hemisphere ambient from the same sky the water reflects; both sides
// lit so that cloth and open shells look right from behind.
inline constexpr const char* kSurfaceFs = R"(
in vec3 vEye, vNormal, vWorld;
uniform vec3 uColor, uLightEye;
uniform int uLit;
uniform float uSpecular;
out vec4 oColor;
void main() {
  if (uLit == 0) {
    oColor = vec4(uColor, 1.0);
    return;
  }
  vec3 n = normalize(vNormal);
  if (!gl_FrontFacing) n = -n;
  if (uLit == 2) {
    // Tank walls: a shade per orientation only, so they frame the water without competing.
    oColor = vec4(uColor * (0.86 + 0.14 * abs((mat3(uInvView) * n).z)), 1.0);
    return;
  }
  vec3 v = normalize(-vEye);
  vec3 l = normalize(uLightEye);
  vec3 nw = mat3(uInvView) * n;
  vec3 ambient = mix(uGround, uSkyZenith, 0.5 + 0.5 * nw.y) * 0.55;
  float diffuse = max(dot(n, l), 0.0);
  float spec = uSpecular * pow(max(dot(n, normalize(l + v)), 0.0), 48.0);
  oColor = vec4(uColor * (ambient + 0.6 * diffuse) + vec3(spec), 1.0);
}
)";

// The ground: a faint grid every uGrid metres that fades into the horizon far from the tank.
inline constexpr const char* kFloorFs = R"(
in vec3 vEye, vNormal, vWorld;
uniform vec3 uColor, uLightEye;
uniform float uGrid, uReach;
uniform vec2 uCenter;
out vec4 oColor;
float grid_line(float u) {
  float w = max(fwidth(u), 1e-6);
  float f = abs(fract(u + 0.5) - 0.5);
  return 1.0 - smoothstep(0.5 * w, 1.5 * w, f);
}
void main() {
  float line = max(grid_line(vWorld.x / uGrid), grid_line(vWorld.z / uGrid));
  vec3 c = uColor * (1.0 - 0.15 * line);
  c *= 0.75 + 0.25 * max(dot(normalize(vNormal), normalize(uLightEye)), 0.0);
  float r = length(vWorld.xz - uCenter) / uReach;
  oColor = vec4(mix(c, uSkyHorizon, smoothstep(0.3, 1.0, r)), 1.0);
}
)";

// Particles as point sprites a little larger than the sphere's projected disc. The disc
// itself is cut out in the fragment shader from the exact centre and radius in pixels, not
// from gl_PointCoord: drivers round the point size, which would shrink small spheres.
inline constexpr const char* kSpriteVs = R"(
layout(location = 0) in vec3 aPos;
uniform mat4 uView, uProj;
uniform vec2 uViewport;
uniform float uRadius, uFocal;
flat out vec3 vCenter;
flat out vec2 vCenterPx;
flat out float vRadiusPx;
void main() {
  vec4 e = uView * vec4(aPos, 1.0);
  vCenter = e.xyz;
  gl_Position = uProj * e;
  vCenterPx = (gl_Position.xy / gl_Position.w * 0.5 + 0.5) * uViewport;
  vRadiusPx = uRadius * uFocal / max(-e.z, 1e-6);
  gl_PointSize = 2.0 * ceil(vRadiusPx) + 2.0;
}
)";

// The sphere behind a sprite fragment, and the test against the opaque scene (bodies, floor,
// walls) drawn before, so that hidden water adds neither depth nor thickness.
inline constexpr const char* kSpriteCommon = R"(
flat in vec3 vCenter;
flat in vec2 vCenterPx;
flat in float vRadiusPx;
uniform mat4 uProj;
uniform float uRadius;
uniform sampler2D uSceneDepth;
bool sphere_point(out vec3 p, out vec3 n) {
  vec2 c = (gl_FragCoord.xy - vCenterPx) / vRadiusPx;
  float r2 = dot(c, c);
  if (r2 > 1.0) return false;
  n = vec3(c, sqrt(1.0 - r2));
  p = vCenter + n * uRadius;
  return true;
}
float window_depth(vec3 p) {
  vec4 clip = uProj * vec4(p, 1.0);
  return clip.z / clip.w * 0.5 + 0.5;
}
bool behind_scene(float wz) {
  return wz >= texelFetch(uSceneDepth, ivec2(gl_FragCoord.xy), 0).r;
}
)";

// Pass 1: eye depth of the nearest sphere surface (0 = no fluid).
inline constexpr const char* kSpriteDepthFs = R"(
out float oDepth;
void main() {
  vec3 p, n;
  if (!sphere_point(p, n)) discard;
  float wz = window_depth(p);
  if (behind_scene(wz)) discard;
  gl_FragDepth = wz;
  oDepth = -p.z;
}
)";

// Pass 2: thickness, the length of the view ray inside each sphere, summed by blending.
// A particle stands for (2r)^3 of water, the sphere for 4/3 pi r^3 of it: the chord is
// scaled by 6 / pi so that the sum is metres of water along the ray.
inline constexpr const char* kSpriteThicknessFs = R"(
out float oThickness;
void main() {
  vec3 p, n;
  if (!sphere_point(p, n)) discard;
  if (behind_scene(window_depth(p))) discard;
  oThickness = 2.0 * n.z * uRadius * (6.0 / 3.14159265);
}
)";

// Particles drawn as lit spheres into the opaque scene (the viewer's particle mode).
inline constexpr const char* kSpriteShadedFs = R"(
uniform vec3 uColor, uLightEye;
out vec4 oColor;
void main() {
  vec3 p, n;
  if (!sphere_point(p, n)) discard;
  gl_FragDepth = window_depth(p);
  vec3 l = normalize(uLightEye);
  float diffuse = max(dot(n, l), 0.0);
  float spec = pow(max(dot(n, normalize(l + normalize(-p))), 0.0), 60.0);
  oColor = vec4(uColor * (0.35 + 0.65 * diffuse) + vec3(0.35 * spec), 1.0);
}
)";

// Pass 3: one sweep of the separable bilateral filter on eye depth. The spatial Gaussian
// spans uWorldRadius in the world, so distant water is smoothed over fewer pixels; the
// range Gaussian keeps layers at different depths apart, and empty pixels never enter, so
// silhouettes neither shrink nor bleed into the background.
inline constexpr const char* kBilateralFs = R"(
uniform sampler2D uDepth;
uniform ivec2 uDir;
uniform float uWorldRadius, uFocal, uMaxPx, uRangeSigma;
out float oDepth;
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  ivec2 size = textureSize(uDepth, 0);
  float d = texelFetch(uDepth, p, 0).r;
  if (d <= 0.0) {
    oDepth = 0.0;
    return;
  }
  float rpx = min(uWorldRadius * uFocal / d, uMaxPx);
  int n = int(ceil(rpx));
  float sigma = max(0.5 * rpx, 0.5);
  float ks = 0.5 / (sigma * sigma);
  float kr = 0.5 / (uRangeSigma * uRangeSigma);
  float sum = 0.0, wsum = 0.0;
  for (int i = -n; i <= n; ++i) {
    float s = texelFetch(uDepth, clamp(p + uDir * i, ivec2(0), size - 1), 0).r;
    if (s <= 0.0) continue;
    float dz = s - d;
    float w = exp(-float(i * i) * ks - dz * dz * kr);
    sum += s * w;
    wsum += w;
  }
  oDepth = sum / wsum;
}
)";

// Pass 3b: Gaussian blur of the thickness, one sweep, over about a particle diameter: the
// sum of sphere chords is lumpy at the particle scale, and Beer-Lambert would show every
// particle as a dark dot.
inline constexpr const char* kThicknessBlurFs = R"(
uniform sampler2D uThickness, uDepth;
uniform ivec2 uDir;
uniform float uWorldRadius, uFocal, uMaxPx;
out float oThickness;
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  ivec2 size = textureSize(uThickness, 0);
  float d = texelFetch(uDepth, p, 0).r;
  if (d <= 0.0) {
    oThickness = 0.0;
    return;
  }
  float rpx = min(uWorldRadius * uFocal / d, uMaxPx);
  int n = int(ceil(rpx));
  float k = 0.5 / pow(max(0.5 * rpx, 0.5), 2.0);
  float sum = 0.0, wsum = 0.0;
  for (int i = -n; i <= n; ++i) {
    float w = exp(-float(i * i) * k);
    sum += w * texelFetch(uThickness, clamp(p + uDir * i, ivec2(0), size - 1), 0).r;
    wsum += w;
  }
  oThickness = sum / wsum;
}
)";

// Pass 4: eye-space normals from the smoothed depth. Of the forward and backward differences
// the one with the smaller depth step is taken, so normals do not reach across silhouettes.
inline constexpr const char* kNormalsFs = R"(
uniform sampler2D uDepth;
out vec4 oNormal;
float depth_at(ivec2 q) {
  ivec2 size = textureSize(uDepth, 0);
  if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) return 0.0;
  return texelFetch(uDepth, q, 0).r;
}
vec3 step_along(ivec2 p, ivec2 e, vec3 c, float d) {
  float df = depth_at(p + e), db = depth_at(p - e);
  vec3 f = eye_position(vec2(p + e) + 0.5, df) - c;
  vec3 b = c - eye_position(vec2(p - e) + 0.5, db);
  if (df <= 0.0 && db <= 0.0) return eye_position(vec2(p + e) + 0.5, d) - c;
  if (df <= 0.0) return b;
  if (db <= 0.0) return f;
  return abs(f.z) < abs(b.z) ? f : b;
}
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  float d = depth_at(p);
  if (d <= 0.0) {
    oNormal = vec4(0.0);
    return;
  }
  vec3 c = eye_position(vec2(p) + 0.5, d);
  vec3 n = cross(step_along(p, ivec2(1, 0), c, d), step_along(p, ivec2(0, 1), c, d));
  oNormal = vec4(normalize(n), d);
}
)";

// Pass 5: the water over the scene. Fresnel (Schlick, F0 = 0.02 for water) blends the sky's
// reflection with the refracted background, which is looked up at an offset along the
// normal growing with thickness and attenuated by Beer-Lambert absorption per channel.
inline constexpr const char* kCompositeFs = R"(
uniform sampler2D uScene, uSceneDepth, uNormal, uThickness;
uniform mat4 uProj;
uniform vec3 uLightEye, uAbsorb, uWaterColor;
uniform float uRefract, uFocal;
out vec4 oColor;
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  vec4 nd = texelFetch(uNormal, p, 0);
  vec3 bg = texelFetch(uScene, p, 0).rgb;
  if (nd.w <= 0.0) {
    oColor = vec4(bg, 1.0);
    return;
  }
  vec3 n = normalize(nd.xyz);
  vec3 pos = eye_position(gl_FragCoord.xy, nd.w);
  vec3 v = normalize(-pos);
  float t = texelFetch(uThickness, p, 0).r;

  vec2 off = n.xy * (uRefract * t * uFocal / nd.w);
  float lim = 0.05 * uViewport.y;
  if (length(off) > lim) off *= lim / length(off);
  vec2 uv = (gl_FragCoord.xy + off) / uViewport;
  vec4 clip = uProj * vec4(pos, 1.0);
  // What stands in front of the water must not show through it.
  if (texture(uSceneDepth, uv).r < clip.z / clip.w * 0.5 + 0.5) uv = gl_FragCoord.xy / uViewport;
  vec3 transmit = exp(-uAbsorb * t);
  vec3 l = normalize(uLightEye);
  vec3 body = uWaterColor * (0.6 + 0.4 * max(dot(n, l), 0.0));
  vec3 refracted = texture(uScene, uv).rgb * transmit + body * (1.0 - transmit);

  vec3 reflected = sky(normalize(mat3(uInvView) * reflect(-v, n)));
  float fresnel = 0.02 + 0.98 * pow(1.0 - max(dot(n, v), 0.0), 5.0);
  float spec = 0.9 * pow(max(dot(n, normalize(l + v)), 0.0), 150.0);
  oColor = vec4(mix(refracted, reflected, fresnel) + vec3(spec), 1.0);
}
)";

// Text: a quad in NDC textured with a coverage mask, or a solid quad behind it.
inline constexpr const char* kTextVs = R"(
uniform vec4 uRect;  // x0, y0, x1, y1 in NDC
out vec2 vUv;
void main() {
  vec2 c = vec2(float(gl_VertexID & 1), float((gl_VertexID >> 1) & 1));
  vUv = vec2(c.x, 1.0 - c.y);
  gl_Position = vec4(mix(uRect.xy, uRect.zw, c), 0.0, 1.0);
}
)";

inline constexpr const char* kTextFs = R"(
in vec2 vUv;
uniform sampler2D uMask;
uniform vec4 uColor;
uniform int uSolid;
out vec4 oColor;
void main() {
  float a = uSolid != 0 ? 1.0 : texture(uMask, vUv).r;
  oColor = vec4(uColor.rgb, uColor.a * a);
}
)";

}  // namespace sphfem::render::gl
