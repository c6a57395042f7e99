// The sub-cell Hertz layer's solve for one substep, before step.comp
// (force_law::HertzLayer is its CPU twin; docs/physics.md derives it). One
// workgroup. Invocation i takes the surface triangles i, i + N, ...: the
// sphere's penalty on each (sphere_triangle_penalty after a box test, the
// same as step.comp's) goes to layer_touch[t] = {f_t, k_t} (k_t = 0: not
// touching), and its share of their sum F_lin and of the m-weighted a_h and
// E*. Shared-memory trees sum the shares in a fixed order (deterministic).
// Then Newton's steps on the Hertz radius a, kept in a bracket, the same on
// every invocation: each step sums G(delta(a)) = sum_t c_t m_t
// hertz_layer_factor(...) and its slope over the touches the same way.
// layer_out = {n, delta} for step.comp, which multiplies each penalty by its
// hertz_layer_factor. The loops' conditions come from shared sums, so every
// invocation takes the same path (uniform control flow for the barriers).
layout(local_size_x = ORGANSIM_GL_LAYER_SIZE) in;

struct LayerTri {
  ivec4 corners;  // x, y, z: the corners; w unused
  vec4 data;      // {punch radius before the factor (m), E* (Pa), 0, 0}
};

layout(std430, binding = ORGANSIM_GL_B_X_CUR) readonly buffer XCur { vec4 x_cur[]; };
layout(std430, binding = ORGANSIM_GL_B_MASS) readonly buffer Mass { vec4 mass[]; };
layout(std430, binding = ORGANSIM_GL_B_LAYER_TRIS) readonly buffer Tris { LayerTri tris[]; };
layout(std430, binding = ORGANSIM_GL_B_LAYER_TOUCH) buffer Touch { vec4 touch[]; };
layout(std430, binding = ORGANSIM_GL_B_LAYER_OUT) writeonly buffer Out { vec4 layer_out; };
#include "force_law.glsl"

layout(location = ORGANSIM_GL_U_TOOL_A) uniform vec3 u_center;  // the sphere's centre this substep, m
layout(location = ORGANSIM_GL_U_TOOL_RADIUS) uniform float u_radius;
layout(location = ORGANSIM_GL_U_TOOL_K) uniform float u_k;
layout(location = ORGANSIM_GL_U_LAYER_TRIS) uniform int u_ntri;
layout(location = ORGANSIM_GL_U_LAYER_FACTOR) uniform float u_punch_factor;

shared vec4 s_a[ORGANSIM_GL_LAYER_SIZE];
shared vec4 s_b[ORGANSIM_GL_LAYER_SIZE];

// Sums s_a and s_b over the workgroup into entry 0 (fixed tree order) and
// returns them to every invocation.
void reduce(uint lane, inout vec4 a, inout vec4 b) {
  s_a[lane] = a;
  s_b[lane] = b;
  memoryBarrierShared();
  barrier();
  for (uint half_size = ORGANSIM_GL_LAYER_SIZE / 2; half_size > 0; half_size /= 2) {
    if (lane < half_size) {
      s_a[lane] += s_a[lane + half_size];
      s_b[lane] += s_b[lane + half_size];
    }
    memoryBarrierShared();
    barrier();
  }
  a = s_a[0];
  b = s_b[0];
  barrier();  // every invocation has read entry 0 before the next reduce writes it
}

float hertz_force_at(float a, float e_star) { return 4.0 * e_star * a * a * a / (3.0 * u_radius); }

// {G(delta), its slope sum k_t c_t^2 over the penalties still pressing} over
// this invocation's triangles, then summed.
vec2 along(uint lane, vec3 n, float delta) {
  vec4 g = vec4(0.0), unused = vec4(0.0);
  for (int t = int(lane); t < u_ntri; t += ORGANSIM_GL_LAYER_SIZE) {
    const vec4 e = touch[t];
    const float m = length(e.xyz);
    if (!(m > 0.0)) continue;
    const float c = dot(e.xyz, n) / m;
    g.x += c * m * hertz_layer_factor(m, e.w, c, delta);
    if (m - e.w * c * delta > 0.0) g.y += e.w * c * c;
  }
  reduce(lane, g, unused);
  return g.xy;
}

void main() {
  const uint lane = gl_LocalInvocationID.x;
  const float r2 = u_radius * u_radius;
  vec4 sum = vec4(0.0);     // {F_lin, sum m}
  vec4 weighted = vec4(0.0);  // {sum m a_h, sum m E*, 0, 0}
  for (int t = int(lane); t < u_ntri; t += ORGANSIM_GL_LAYER_SIZE) {
    const LayerTri tri = tris[t];
    const vec3 a = x_cur[tri.corners.x].xyz, b = x_cur[tri.corners.y].xyz, c = x_cur[tri.corners.z].xyz;
    const vec3 gap = max(min(min(a, b), c) - u_center, vec3(0.0)) + max(u_center - max(max(a, b), c), vec3(0.0));
    vec4 entry = vec4(0.0);
    if (dot(gap, gap) < r2) {
      const vec3 share = vec3(mass[tri.corners.x].w, mass[tri.corners.y].w, mass[tri.corners.z].w);
      vec3 f, w;
      if (sphere_triangle_penalty(u_center, u_radius, a, b, c, u_k, share, f, w)) {
        const float m = length(f);
        entry = vec4(f, u_k * min(min(share.x, share.y), share.z));
        sum += vec4(f, m);
        weighted.xy += m * tri.data.xy;
      }
    }
    touch[t] = entry;
  }
  reduce(lane, sum, weighted);
  const float linear = length(sum.xyz);
  if (!(linear > 0.0) || !(sum.w > 0.0)) {
    if (lane == 0) layer_out = vec4(0.0, 0.0, 1.0, 0.0);
    return;
  }
  const vec3 n = sum.xyz / linear;
  const float a_h = u_punch_factor * weighted.x / sum.w, e_star = weighted.y / sum.w;
  // Beyond a_h the offset is constant (force_law::HertzLayer::solve).
  float delta = a_h * a_h / (3.0 * u_radius);
  if (along(lane, n, delta).x < hertz_force_at(a_h, e_star)) {
    float lo = 0.0, hi = a_h, a = a_h;
    for (int iteration = 0; iteration < 40; ++iteration) {
      const float d = hertz_layer_offset_at(a, u_radius, a_h);
      const vec2 g = along(lane, n, d);
      const float value = hertz_force_at(a, e_star) - g.x;
      if (value == 0.0) break;
      if (value < 0.0) lo = a; else hi = a;
      const float slope = 4.0 * e_star * a * a / u_radius + g.y * 2.0 * a * (1.0 - a / a_h) / u_radius;
      float next = slope > 0.0 ? a - value / slope : lo;
      if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
      const bool settled = abs(next - a) <= 1e-6 * a_h;
      a = next;
      if (settled) break;
    }
    delta = hertz_layer_offset_at(a, u_radius, a_h);
  }
  if (lane == 0) layer_out = vec4(n, delta);
}
