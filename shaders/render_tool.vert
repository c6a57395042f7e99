#version 450 core
// The tool: a unit sphere mesh scaled and moved to the tool's pose. A
// capsule (u_end_a != u_end_b) is the same mesh turned so that its poles lie
// along the segment, its upper half moved to u_end_b and its lower half to
// u_end_a: the band of triangles between them becomes the shaft.
layout(location = 0) in vec3 a_unit;  // point on the unit sphere = its normal

uniform mat4 u_view;
uniform mat4 u_projection;
uniform vec3 u_end_a;   // the segment's ends, m (both the centre for a sphere)
uniform vec3 u_end_b;
uniform float u_radius; // m
uniform vec3 u_color;

out vec3 v_position_eye;
out vec3 v_normal_eye;
out vec3 v_color;

void main() {
  const vec3 axis = u_end_b - u_end_a;
  vec3 normal = a_unit;
  vec3 end = u_end_a;
  if (dot(axis, axis) > 0.0) {
    // An orthonormal frame (e1, e2, z) with z along the segment; the mesh's
    // own z (its poles) maps to z.
    const vec3 z = normalize(axis);
    const vec3 helper = abs(z.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
    const vec3 e1 = normalize(cross(helper, z));
    const vec3 e2 = cross(z, e1);
    normal = a_unit.x * e1 + a_unit.y * e2 + a_unit.z * z;
    end = a_unit.z > 0.0 ? u_end_b : u_end_a;
  }
  vec4 eye = u_view * vec4(end + u_radius * normal, 1.0);
  v_position_eye = eye.xyz;
  v_normal_eye = mat3(u_view) * normal;
  v_color = u_color;
  gl_Position = u_projection * eye;
}
