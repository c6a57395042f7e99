#version 450 core
// Two-sided Blinn-Phong with a headlight and a fixed key light in eye space,
// or a flat colour for the wireframe and line overlays. With face colours
// (labels) each triangle takes its own colour, found by gl_PrimitiveID: the
// triangle's index in the draw, i.e. in the face list.
in vec3 v_position_eye;
in vec3 v_normal_eye;
in vec3 v_color;

layout(std430, binding = 4) readonly buffer FaceColors { vec4 face_color[]; };  // nface, when used

uniform bool u_flat;        // wireframe and line passes
uniform vec3 u_flat_color;
uniform bool u_face_colors;

out vec4 frag_color;

void main() {
  if (u_flat) {
    frag_color = vec4(u_flat_color, 1.0);
    return;
  }
  vec3 n = normalize(v_normal_eye);
  if (!gl_FrontFacing) n = -n;  // open surfaces and the inside stay lit
  vec3 to_eye = normalize(-v_position_eye);
  vec3 key = normalize(vec3(0.4, 0.7, 0.6));
  float diffuse = 0.55 * max(dot(n, to_eye), 0.0) + 0.35 * max(dot(n, key), 0.0);
  float specular = 0.25 * pow(max(dot(n, normalize(key + to_eye)), 0.0), 32.0);
  vec3 base = u_face_colors ? face_color[gl_PrimitiveID].rgb : v_color;
  vec3 c = base * (0.25 + diffuse) + vec3(specular);
  frag_color = vec4(min(c, vec3(1.0)), 1.0);
}
