// The sub-cell Hertz layer's first pass each substep (then hertz_layer.comp's
// solve, then the step): one invocation per surface triangle, many
// workgroups. The tool's penalty on triangle t (capsule_triangle_penalty
// after a box test, the same as step.comp's; a sphere's segment has a == b)
// goes to touch[2t] = {f_t, k_t} (k_t = 0: not touching) and touch[2t + 1]
// = {s_t, 0, 0, 0}, its place along the capsule's axis (m; 0 for a sphere),
// and each workgroup writes how many of its
// ORGANSIM_GL_LAYER_SIZE triangles touch, so that the solve's single
// workgroup reads only the blocks in contact instead of every triangle.
layout(local_size_x = ORGANSIM_GL_LAYER_SIZE) in;

struct LayerTri {
  ivec4 corners;  // x, y, z: the corners; w unused
  vec4 data;      // {punch radius before the factor (m), E* (Pa), 0, 0}
};

layout(std430, binding = ORGANSIM_GL_B_X_CUR) readonly buffer XCur { vec4 x_cur[]; };
layout(std430, binding = ORGANSIM_GL_B_MASS) readonly buffer Mass { vec4 mass[]; };
layout(std430, binding = ORGANSIM_GL_B_LAYER_TRIS) readonly buffer Tris { LayerTri tris[]; };
layout(std430, binding = ORGANSIM_GL_B_LAYER_TOUCH) writeonly buffer Touch { vec4 touch[]; };
layout(std430, binding = ORGANSIM_GL_B_LAYER_BLOCKS) writeonly buffer Blocks { uint block_touching[]; };
#include "force_law.glsl"

layout(location = ORGANSIM_GL_U_TOOL_A) uniform vec3 u_a;  // the tool's segment this substep (a == b: a sphere), m
layout(location = ORGANSIM_GL_U_TOOL_B) uniform vec3 u_b;
layout(location = ORGANSIM_GL_U_TOOL_RADIUS) uniform float u_radius;
layout(location = ORGANSIM_GL_U_TOOL_K) uniform float u_k;
layout(location = ORGANSIM_GL_U_LAYER_TRIS) uniform int u_ntri;

shared uint s_touching;

void main() {
  if (gl_LocalInvocationID.x == 0) s_touching = 0u;
  memoryBarrierShared();
  barrier();
  const int t = int(gl_GlobalInvocationID.x);
  if (t < u_ntri) {
    const LayerTri tri = tris[t];
    const vec3 a = x_cur[tri.corners.x].xyz, b = x_cur[tri.corners.y].xyz, c = x_cur[tri.corners.z].xyz;
    const vec3 gap = max(min(min(a, b), c) - max(u_a, u_b), vec3(0.0)) + max(min(u_a, u_b) - max(max(a, b), c), vec3(0.0));
    vec4 entry = vec4(0.0), along = vec4(0.0);
    if (dot(gap, gap) < u_radius * u_radius) {
      const vec3 share = vec3(mass[tri.corners.x].w, mass[tri.corners.y].w, mass[tri.corners.z].w);
      vec3 f, w;
      if (capsule_triangle_penalty(u_a, u_b, u_radius, a, b, c, u_k, share, f, w)) {
        entry = vec4(f, u_k * min(min(share.x, share.y), share.z));
        along.x = segment_axial_position(w.x * a + w.y * b + w.z * c, u_a, u_b);
        atomicAdd(s_touching, 1u);  // an integer count: the order does not matter
      }
    }
    touch[2 * t] = entry;
    touch[2 * t + 1] = along;
  }
  memoryBarrierShared();
  barrier();
  if (gl_LocalInvocationID.x == 0) block_touching[gl_WorkGroupID.x] = s_touching;
}
