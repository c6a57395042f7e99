#version 450 core
// The tool: a unit sphere mesh scaled and moved to the tool's pose.
layout(location = 0) in vec3 a_unit;  // point on the unit sphere = its normal

uniform mat4 u_view;
uniform mat4 u_projection;
uniform vec3 u_center;  // m
uniform float u_radius; // m
uniform vec3 u_color;

out vec3 v_position_eye;
out vec3 v_normal_eye;
out vec3 v_color;

void main() {
  vec4 eye = u_view * vec4(u_center + u_radius * a_unit, 1.0);
  v_position_eye = eye.xyz;
  v_normal_eye = mat3(u_view) * a_unit;
  v_color = u_color;
  gl_Position = u_projection * eye;
}
