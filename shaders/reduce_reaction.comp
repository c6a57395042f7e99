// Sums the per-workgroup tool reaction partials of the last substep of a tick
// into one ring slot of the persistently mapped reaction buffer: 6 floats
// (force, torque) and the contact count. One workgroup; each lane sums a
// strided share in a fixed order, then a shared-memory tree: deterministic.
layout(local_size_x = ORGANSIM_GL_REDUCE_SIZE) in;

layout(std430, binding = ORGANSIM_GL_B_PARTIALS) readonly buffer Partials { vec4 partials[]; };
layout(std430, binding = ORGANSIM_GL_B_REACTION) writeonly buffer Reaction { vec4 reaction[]; };

layout(location = ORGANSIM_GL_U_NPARTIAL) uniform int u_npartial;
layout(location = ORGANSIM_GL_U_SLOT) uniform int u_slot;

shared vec4 s_force[ORGANSIM_GL_REDUCE_SIZE];
shared vec4 s_torque[ORGANSIM_GL_REDUCE_SIZE];

void main() {
  uint lane = gl_LocalInvocationID.x;
  vec4 force = vec4(0.0);
  vec4 torque = vec4(0.0);
  for (int i = int(lane); i < u_npartial; i += ORGANSIM_GL_REDUCE_SIZE) {
    force += partials[2 * i];
    torque += partials[2 * i + 1];
  }
  s_force[lane] = force;
  s_torque[lane] = torque;
  memoryBarrierShared();
  barrier();
  for (uint half_size = ORGANSIM_GL_REDUCE_SIZE / 2; half_size > 0; half_size /= 2) {
    if (lane < half_size) {
      s_force[lane] += s_force[lane + half_size];
      s_torque[lane] += s_torque[lane + half_size];
    }
    memoryBarrierShared();
    barrier();
  }
  if (lane == 0) {
    reaction[2 * u_slot] = s_force[0];
    reaction[2 * u_slot + 1] = s_torque[0];
  }
}
