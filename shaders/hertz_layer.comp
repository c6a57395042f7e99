// The sub-cell layer's solve for one substep, after hertz_layer_touch.comp
// and before the step (force_law::HertzLayer is its CPU twin;
// docs/physics.md derives it). One workgroup. It reads the penalties {f_t,
// k_t} and places s_t along the axis of the blocks of ORGANSIM_GL_LAYER_SIZE
// triangles that the touch pass found in contact (a few of them: the
// triangles are packed in spatial order), invocation i taking entry i of
// each block. Shared-memory trees sum, in a fixed order (deterministic),
// F_lin and the m-weighted a_h and E*, then the places weighted by each
// touch's force along n, then their spread about its mean. With no spread
// along the axis (a sphere, a capsule on its end): Newton's steps on the
// Hertz radius a, kept in a bracket; otherwise the blend of the sphere's
// and the line's law and regula falsi (Illinois) on the force. Either is
// the same on every invocation: each step sums G(delta) = sum_t c_t m_t
// hertz_layer_factor(...) (and its slope) over the touches the same way.
// layer_out = {n, delta} for step.comp, which multiplies each penalty by
// its hertz_layer_factor. The loops' conditions come from shared values, so
// every invocation takes the same path (uniform control flow for the
// barriers).
layout(local_size_x = ORGANSIM_GL_LAYER_SIZE) in;

struct LayerTri {
  ivec4 corners;  // x, y, z: the corners; w unused
  vec4 data;      // {punch radius before the factor (m), E* (Pa), 0, 0}
};

layout(std430, binding = ORGANSIM_GL_B_LAYER_TRIS) readonly buffer Tris { LayerTri tris[]; };
layout(std430, binding = ORGANSIM_GL_B_LAYER_TOUCH) readonly buffer Touch { vec4 touch[]; };
layout(std430, binding = ORGANSIM_GL_B_LAYER_BLOCKS) readonly buffer Blocks { uint block_touching[]; };
layout(std430, binding = ORGANSIM_GL_B_LAYER_OUT) writeonly buffer Out { vec4 layer_out; };
#include "force_law.glsl"

layout(location = ORGANSIM_GL_U_TOOL_RADIUS) uniform float u_radius;
layout(location = ORGANSIM_GL_U_LAYER_TRIS) uniform int u_ntri;
layout(location = ORGANSIM_GL_U_LAYER_FACTOR) uniform float u_punch_factor;
layout(location = ORGANSIM_GL_U_LAYER_LINE_FACTOR) uniform float u_line_factor;

shared vec4 s_a[ORGANSIM_GL_LAYER_SIZE];
shared vec4 s_b[ORGANSIM_GL_LAYER_SIZE];
shared uint s_scan[ORGANSIM_GL_LAYER_SIZE];
shared uint s_blocks[ORGANSIM_GL_LAYER_MAX_BLOCKS];  // the blocks in contact, ascending

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

// delta(F) of the sphere's and the line's laws blended by beta
// (force_law::HertzLayer::offset_for), for a contact of length L.
float blended_offset(float force, float beta, float contact_length, float e_star, float a_h, float c_line) {
  return (1.0 - beta) * hertz_layer_offset(force, e_star, u_radius, a_h) +
         beta * line_layer_offset(force / contact_length, e_star, u_radius, c_line);
}

// The exclusive prefix sum of v over the lanes (Hillis-Steele in shared
// memory), and in `total` the sum over all of them.
uint exclusive_scan(uint lane, uint v, out uint total) {
  s_scan[lane] = v;
  memoryBarrierShared();
  barrier();
  for (uint d = 1; d < ORGANSIM_GL_LAYER_SIZE; d *= 2) {
    const uint add = lane >= d ? s_scan[lane - d] : 0u;
    memoryBarrierShared();
    barrier();
    s_scan[lane] += add;
    memoryBarrierShared();
    barrier();
  }
  total = s_scan[ORGANSIM_GL_LAYER_SIZE - 1];
  const uint before = s_scan[lane] - v;
  barrier();  // every invocation has read s_scan before it is written again
  return before;
}

// This lane's penalty in the i-th block in contact: {f_t, k_t}, and its triangle.
vec4 touch_at(uint lane, uint i, out int t) {
  t = int(s_blocks[i] * ORGANSIM_GL_LAYER_SIZE + lane);
  return t < u_ntri ? touch[2 * t] : vec4(0.0);
}

// {G(delta), its slope sum k_t c_t^2 over the penalties still pressing} over
// this invocation's entries of the blocks in contact, then summed.
vec2 along(uint lane, uint nblocks, vec3 n, float delta) {
  vec4 g = vec4(0.0), unused = vec4(0.0);
  for (uint i = 0; i < nblocks; ++i) {
    int t;
    const vec4 e = touch_at(lane, i, t);
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
  // The blocks in contact, in ascending order: lane i looks at a contiguous
  // range of blocks, and a prefix sum of the counts places its finds.
  const int nblock_all = (u_ntri + ORGANSIM_GL_LAYER_SIZE - 1) / ORGANSIM_GL_LAYER_SIZE;
  const int per_lane = (nblock_all + ORGANSIM_GL_LAYER_SIZE - 1) / ORGANSIM_GL_LAYER_SIZE;
  const int first = int(lane) * per_lane, last = min(first + per_lane, nblock_all);
  uint mine = 0u;
  for (int b = first; b < last; ++b) mine += block_touching[b] > 0u ? 1u : 0u;
  uint nblocks;
  uint at = exclusive_scan(lane, mine, nblocks);
  for (int b = first; b < last; ++b) {
    if (block_touching[b] > 0u) s_blocks[at++] = uint(b);
  }
  memoryBarrierShared();
  barrier();

  vec4 sum = vec4(0.0);       // {F_lin, sum m}
  vec4 weighted = vec4(0.0);  // {sum m a_h, sum m E*, 0, 0}
  for (uint i = 0; i < nblocks; ++i) {
    int t;
    const vec4 e = touch_at(lane, i, t);
    const float m = length(e.xyz);
    if (!(m > 0.0)) continue;
    sum += vec4(e.xyz, m);
    weighted.xy += m * tris[t].data.xy;
  }
  reduce(lane, sum, weighted);
  const float linear = length(sum.xyz);
  if (!(linear > 0.0) || !(sum.w > 0.0)) {
    if (lane == 0) layer_out = vec4(0.0, 0.0, 1.0, 0.0);
    return;
  }
  const vec3 n = sum.xyz / linear;
  const float a_h = u_punch_factor * weighted.x / sum.w, e_star = weighted.y / sum.w;
  // The places along the axis weighted by each touch's force along n
  // (force_law::HertzLayer::contact_length): their mean, then their spread
  // about it in a second pass (sum w s^2 - (sum w s)^2 / sum w would cancel
  // to float noise where every place is the same).
  vec4 moments = vec4(0.0), spread = vec4(0.0), unused = vec4(0.0);  // {sum w, sum w s}, {sum w (s - mean)^2}
  for (uint i = 0; i < nblocks; ++i) {
    int t;
    const vec4 e = touch_at(lane, i, t);
    const float w = max(0.0, dot(e.xyz, n));
    moments.xy += w * vec2(1.0, touch[2 * t + 1].x);
  }
  reduce(lane, moments, unused);
  const float mean = moments.x > 0.0 ? moments.y / moments.x : 0.0;
  for (uint i = 0; i < nblocks; ++i) {
    int t;
    const vec4 e = touch_at(lane, i, t);
    const float w = max(0.0, dot(e.xyz, n));
    const float d = touch[2 * t + 1].x - mean;
    spread.x += w * d * d;
  }
  reduce(lane, spread, unused);
  const float variance = moments.x > 0.0 ? spread.x / moments.x : 0.0;
  const float contact_length = variance > 0.0 ? sqrt(12.0 * variance) : 0.0;
  const float beta = contact_length > 0.0 ? min(1.0, contact_length / (2.0 * a_h)) : 0.0;
  float delta;
  if (beta > 0.0) {
    // The blend (force_law::HertzLayer::offset_for); h(F) = F - G(delta(F))
    // rises with F from -|F_lin| at 0 to >= 0 at |F_lin|.
    const float c_line = u_line_factor * weighted.x / sum.w;
    float lo = 0.0, hi = linear, h_lo = -linear, force = linear;
    delta = blended_offset(linear, beta, contact_length, e_star, a_h, c_line);
    float h_hi = linear - along(lane, nblocks, n, delta).x;
    for (int iteration = 0; iteration < 60 && h_hi > 0.0 && hi - lo > 1e-6 * hi; ++iteration) {
      force = hi - h_hi * (hi - lo) / (h_hi - h_lo);
      if (!(force > lo && force < hi)) force = 0.5 * (lo + hi);
      delta = blended_offset(force, beta, contact_length, e_star, a_h, c_line);
      const float h = force - along(lane, nblocks, n, delta).x;
      if (h == 0.0) break;
      if (h < 0.0) {
        lo = force, h_lo = h, h_hi /= 2.0;
      } else {
        hi = force, h_hi = h, h_lo /= 2.0;
      }
    }
  } else {
    // Beyond min(a_h, R / 2) the offset is constant (force_law::HertzLayer::solve).
    const float a_max = min(a_h, kLayerContactLimit * u_radius);
    delta = hertz_layer_held(u_radius, a_h);
    if (along(lane, nblocks, n, delta).x < hertz_force_at(a_max, e_star)) {
      float lo = 0.0, hi = a_max, a = a_max;
      for (int iteration = 0; iteration < 40; ++iteration) {
        const float d = hertz_layer_offset_at(a, u_radius, a_h);
        const vec2 g = along(lane, nblocks, n, d);
        const float value = hertz_force_at(a, e_star) - g.x;
        if (value == 0.0) break;
        if (value < 0.0) lo = a; else hi = a;
        const float slope = 4.0 * e_star * a * a / u_radius + g.y * 2.0 * a * (1.0 - a / a_h) / u_radius;
        float next = slope > 0.0 ? a - value / slope : lo;
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        const bool settled = abs(next - a) <= 1e-6 * a_max;
        a = next;
        if (settled) break;
      }
      delta = hertz_layer_offset_at(a, u_radius, a_h);
    }
  }
  if (lane == 0) layer_out = vec4(n, delta);
}
