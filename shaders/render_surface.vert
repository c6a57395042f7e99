#version 450 core
// Boundary surface by vertex pulling: gl_VertexID is the point id, positions
// come from a storage buffer (organsim's own upload on the CPU backend, or the
// simulation's position buffer on the GL backend), so nothing is copied into
// vertex attributes. Smooth normals are summed here from each point's ring of
// boundary faces (area-weighted: the cross products are not normalised).

layout(std430, binding = 0) readonly buffer Positions { float position[]; };
layout(std430, binding = 1) readonly buffer RingOffset { int ring_offset[]; };  // npoint + 1
layout(std430, binding = 2) readonly buffer RingPairs { int ring_pair[]; };     // 2 per ring face
layout(std430, binding = 3) readonly buffer Colors { vec4 point_color[]; };     // npoint, when used

uniform mat4 u_view;
uniform mat4 u_projection;
uniform int u_stride;        // floats between consecutive points (3 or 4)
uniform int u_offset;        // float index of point 0
uniform bool u_point_colors;
uniform vec3 u_color;

out vec3 v_position_eye;
out vec3 v_normal_eye;
out vec3 v_color;

vec3 point(int i) {
  int k = u_offset + i * u_stride;
  return vec3(position[k], position[k + 1], position[k + 2]);
}

void main() {
  int i = gl_VertexID;
  vec3 p = point(i);
  vec3 n = vec3(0.0);
  for (int r = ring_offset[i]; r < ring_offset[i + 1]; ++r) {
    n += cross(point(ring_pair[2 * r]) - p, point(ring_pair[2 * r + 1]) - p);
  }
  vec4 eye = u_view * vec4(p, 1.0);
  v_position_eye = eye.xyz;
  v_normal_eye = mat3(u_view) * n;  // the view is a rotation + translation
  v_color = u_point_colors ? point_color[i].rgb : u_color;
  gl_Position = u_projection * eye;
}
