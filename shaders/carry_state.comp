// A topology change's new lanes, filled on the GPU (GlBackend::adopt): lane
// u_first + k of the new version's x_t and d_t gets those of the old
// version's point from_old[k] (an appended point's Model::origin followed back
// to a point the old version had; a padding lane the last point's). The old
// points' own state is copied as one block beside this, so an adopt never
// reads the state back.
layout(local_size_x = ORGANSIM_GL_CHUNK) in;

layout(std430, binding = ORGANSIM_GL_B_X_CUR) readonly buffer XOld { vec4 x_old[]; };
layout(std430, binding = ORGANSIM_GL_B_D_CUR) readonly buffer DOld { vec4 d_old[]; };
layout(std430, binding = ORGANSIM_GL_B_X_NEXT) writeonly buffer XNew { vec4 x_new[]; };
layout(std430, binding = ORGANSIM_GL_B_D_NEXT) writeonly buffer DNew { vec4 d_new[]; };
layout(std430, binding = ORGANSIM_GL_B_CARRY) readonly buffer From { int from_old[]; };

layout(location = ORGANSIM_GL_U_CARRY_FIRST) uniform int u_first;
layout(location = ORGANSIM_GL_U_CARRY_COUNT) uniform int u_count;

void main() {
  int k = int(gl_GlobalInvocationID.x);
  if (k >= u_count) return;
  int from = from_old[k];
  x_new[u_first + k] = x_old[from];
  d_new[u_first + k] = d_old[from];
}
