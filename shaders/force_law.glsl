// The force law's GLSL twin of core/physics/force_law.h: the same per-element
// formulas, in float, included by name (core/gl/shader_sources.cpp) by every
// kernel that evaluates them (step.comp, nodal_pressure.comp,
// shear_smoothing.comp), so the shaders cannot drift from the CPU's law.
// tests/gl compares every GL force with the double-precision reference.

// Tension of a spring with its damper, N: k (L - r) + d (closing rate).
float spring_tension(float k, float d, float len, float rest, float closing_rate) {
  return k * (len - rest) + d * closing_rate;
}

// A suture pulls only: no force while slack, and its damper never pushes.
float suture_tension(float tension, float len, float rest) {
  return len > rest && tension > 0.0 ? tension : 0.0;
}

// Pressure of a volume term, Pa: k (V - V_r); the force on x_i is -p dV/dx_i.
float volume_pressure(float k, float volume, float rest_volume) { return k * (volume - rest_volume); }

// A tet's pressure in the averaged nodal term: the mean of its corners'.
float tet_pressure_from_nodal(float q0, float q1, float q2, float q3) { return 0.25 * (q0 + q1 + q2 + q3); }

// The shear element (nu < 1/4): where the barrier -ln J hands over to its
// quadratic extension (force_law::kShearElementMinJ).
const float kShearMinJ = 0.5;

// cof F = J F^-T: column k is the cross product of F's other two columns.
mat3 shear_cofactor(mat3 F) { return mat3(cross(F[1], F[2]), cross(F[2], F[0]), cross(F[0], F[1])); }

// phi'(J): -1/J from J_min up, its quadratic extension's slope below.
float shear_barrier_slope(float J) {
  return J >= kShearMinJ ? -1.0 / J : (J - 2.0 * kShearMinJ) / (kShearMinJ * kShearMinJ);
}

// P(F) = F + phi'(J) cof F, the first Piola-Kirchhoff stress per unit k.
mat3 shear_stress(mat3 F) {
  const mat3 cof = shear_cofactor(F);
  return F + shear_barrier_slope(dot(F[0], cof[0])) * cof;
}

// Push contact of a sphere on a point at `offset` = x - c: k (R - |offset|)
// along offset (+z at the exact centre); false outside the sphere.
bool push_penalty(vec3 offset, float radius, float k, out vec3 f) {
  const float dist = length(offset);
  f = vec3(0.0);
  if (!(dist < radius)) return false;
  const vec3 n = dist > 0.0 ? offset / dist : vec3(0.0, 0.0, 1.0);
  f = k * (radius - dist) * n;
  return true;
}

// Closest point of the triangle (a, b, c) to p as barycentric weights
// (force_law::triangle_closest_weights: the Voronoi regions of vertices,
// edges and face).
vec3 triangle_closest_weights(vec3 p, vec3 a, vec3 b, vec3 c) {
  const vec3 ab = b - a, ac = c - a, ap = p - a;
  const float d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return vec3(1.0, 0.0, 0.0);
  const vec3 bp = p - b;
  const float d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return vec3(0.0, 1.0, 0.0);
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const float v = d1 - d3 > 0.0 ? d1 / (d1 - d3) : 0.0;
    return vec3(1.0 - v, v, 0.0);
  }
  const vec3 cp = p - c;
  const float d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return vec3(0.0, 0.0, 1.0);
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const float v = d2 - d6 > 0.0 ? d2 / (d2 - d6) : 0.0;
    return vec3(1.0 - v, 0.0, v);
  }
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
    const float den = (d4 - d3) + (d5 - d6);
    const float v = den > 0.0 ? (d4 - d3) / den : 0.0;
    return vec3(0.0, 1.0 - v, v);
  }
  const float sum = va + vb + vc;
  if (!(sum > 0.0)) return vec3(1.0, 0.0, 0.0);
  const float v = vb / sum, u = vc / sum;
  return vec3(1.0 - v - u, v, u);
}

// Surface contact of a sphere with one boundary triangle
// (force_law::sphere_triangle_penalty): the penalty k_t (R - |q - c|) n at
// the closest point q = sum w_i x_i, k_t = k min_i share_i; corner i
// receives w_i f. False (f = 0) outside the sphere.
bool sphere_triangle_penalty(vec3 center, float radius, vec3 x0, vec3 x1, vec3 x2, float k, vec3 share,
                             out vec3 f, out vec3 w) {
  f = vec3(0.0);
  w = triangle_closest_weights(center, x0, x1, x2);
  const vec3 q = w.x * x0 + w.y * x1 + w.z * x2;
  const vec3 offset = q - center;
  const float dist = length(offset);
  if (!(dist < radius)) return false;
  vec3 n = vec3(0.0, 0.0, -1.0);
  if (dist > 0.0) {
    n = offset / dist;
  } else {
    const vec3 outward = cross(x1 - x0, x2 - x0);
    if (length(outward) > 0.0) n = -normalize(outward);
  }
  f = k * min(min(share.x, share.y), share.z) * (radius - dist) * n;
  return true;
}

// A pulling tool's attachment spring: k (target - x).
vec3 pull_attachment(vec3 target, vec3 x, float k) { return k * (target - x); }
