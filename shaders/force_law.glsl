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

// The sub-cell Hertz layer (force_law::hertz_layer_offset_at,
// hertz_layer_factor; solved per substep by hertz_layer.comp): the offset
// at Hertz radius a <= a_h, and a touching penalty's factor with the sphere
// moved back by delta.
float hertz_layer_offset_at(float a, float radius, float punch_radius) {
  return a * a / radius - 2.0 * a * a * a / (3.0 * radius * punch_radius);
}
// force_law::kLayerContactLimit: the largest contact radius the layer's
// laws follow, as a share of the tool's radius.
const float kLayerContactLimit = 0.5;
// The offset held beyond the largest Hertz radius min(a_h, R / 2).
float hertz_layer_held(float radius, float punch_radius) {
  const float limit = kLayerContactLimit * radius;
  if (punch_radius <= limit) return punch_radius * punch_radius / (3.0 * radius);
  return hertz_layer_offset_at(limit, radius, punch_radius);
}
// delta(F) (force_law::hertz_layer_offset).
float hertz_layer_offset(float force, float e_star, float radius, float punch_radius) {
  if (!(force > 0.0)) return 0.0;
  const float a = pow(3.0 * force * radius / (4.0 * e_star), 1.0 / 3.0);
  if (a >= min(punch_radius, kLayerContactLimit * radius)) return hertz_layer_held(radius, punch_radius);
  return a * a / radius - force / (2.0 * e_star * punch_radius);
}
float hertz_layer_factor(float m, float k, float c, float delta) {
  if (!(m > 0.0)) return 0.0;
  const float lowered = m - k * c * delta;
  return lowered > 0.0 ? lowered / m : 0.0;
}

// The sub-cell line layer (force_law::line_layer_offset): a capsule's shaft
// pressed by P N/m, the strip punch's half-width c.
float line_layer_offset(float force_per_length, float e_star, float radius, float half_width) {
  if (!(force_per_length > 0.0)) return 0.0;
  const float b = sqrt(4.0 * force_per_length * radius / (3.14159265358979 * e_star));
  const float limit = kLayerContactLimit * radius;
  if (b >= half_width && half_width <= limit) return half_width * half_width / (4.0 * radius);
  const float held = min(b, limit);
  return held * held / (2.0 * radius) * (log(half_width / held) + 0.5);
}

// The capsule tool (force_law.h's capsule section): the segment a-b swept by R.

// The point of the segment a-b closest to p; exactly a when a == b.
vec3 segment_closest_point(vec3 p, vec3 a, vec3 b) {
  const vec3 ab = b - a;
  const float len2 = dot(ab, ab);
  if (!(len2 > 0.0)) return a;
  return a + clamp(dot(ab, p - a) / len2, 0.0, 1.0) * ab;
}

// Where along the segment a-b its point closest to p lies, m
// (force_law::segment_axial_position; 0 when a == b).
float segment_axial_position(vec3 p, vec3 a, vec3 b) {
  const vec3 ab = b - a;
  const float len2 = dot(ab, ab);
  if (!(len2 > 0.0)) return 0.0;
  return clamp(dot(ab, p - a) / len2, 0.0, 1.0) * sqrt(len2);
}

// The closest points of the segments p1-q1 and p2-q2 as parameters (s, t)
// (force_law::segments_closest).
vec2 segments_closest(vec3 p1, vec3 q1, vec3 p2, vec3 q2) {
  const vec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const float a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r);
  if (!(a > 0.0)) return vec2(0.0, e > 0.0 ? clamp(f / e, 0.0, 1.0) : 0.0);
  const float c = dot(d1, r);
  if (!(e > 0.0)) return vec2(clamp(-c / a, 0.0, 1.0), 0.0);
  const float b = dot(d1, d2), denom = a * e - b * b;
  float s = denom > 0.0 ? clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
  float t = (b * s + f) / e;
  if (t < 0.0) {
    t = 0.0;
    s = clamp(-c / a, 0.0, 1.0);
  } else if (t > 1.0) {
    t = 1.0;
    s = clamp((b - c) / a, 0.0, 1.0);
  }
  return vec2(s, t);
}

float triangle_distance2(vec3 p, vec3 x0, vec3 x1, vec3 x2) {
  const vec3 w = triangle_closest_weights(p, x0, x1, x2);
  const vec3 d = w.x * x0 + w.y * x1 + w.z * x2 - p;
  return dot(d, d);
}

// The point of the segment a-b closest to the triangle
// (force_law::segment_point_closest_to_triangle): the crossing point when
// the segment passes through it, else the nearest of the ends and the
// closest points to the three edges, the first on a tie.
vec3 segment_point_closest_to_triangle(vec3 a, vec3 b, vec3 x0, vec3 x1, vec3 x2, out bool crossing) {
  crossing = false;
  const vec3 outward = cross(x1 - x0, x2 - x0);
  const float da = dot(outward, a - x0), db = dot(outward, b - x0);
  if (((da <= 0.0 && db >= 0.0) || (da >= 0.0 && db <= 0.0)) && da != db) {
    const vec3 p = a + (da / (da - db)) * (b - a);
    if (dot(outward, cross(x1 - x0, p - x0)) >= 0.0 && dot(outward, cross(x2 - x1, p - x1)) >= 0.0 &&
        dot(outward, cross(x0 - x2, p - x2)) >= 0.0) {
      crossing = true;
      return p;
    }
  }
  vec3 best = a;
  float best2 = triangle_distance2(a, x0, x1, x2);
  const float b2 = triangle_distance2(b, x0, x1, x2);
  if (b2 < best2) {
    best = b;
    best2 = b2;
  }
  for (int e = 0; e < 3; ++e) {
    const vec3 u = e == 0 ? x0 : e == 1 ? x1 : x2;
    const vec3 v = e == 0 ? x1 : e == 1 ? x2 : x0;
    const vec2 st = segments_closest(a, b, u, v);
    const vec3 ps = a + st.x * (b - a);
    const vec3 d = u + st.y * (v - u) - ps;
    const float d2 = dot(d, d);
    if (d2 < best2) {
      best = ps;
      best2 = d2;
    }
  }
  return best;
}

// Surface contact of a capsule with one triangle
// (force_law::capsule_triangle_penalty): the sphere's contact centred at the
// segment's closest point; a segment through the triangle pushes along the
// inward normal with k_t R; a == b is the sphere.
bool capsule_triangle_penalty(vec3 a, vec3 b, float radius, vec3 x0, vec3 x1, vec3 x2, float k, vec3 share,
                              out vec3 f, out vec3 w) {
  if (a == b) return sphere_triangle_penalty(a, radius, x0, x1, x2, k, share, f, w);
  bool crossing;
  const vec3 p = segment_point_closest_to_triangle(a, b, x0, x1, x2, crossing);
  if (!crossing) return sphere_triangle_penalty(p, radius, x0, x1, x2, k, share, f, w);
  w = triangle_closest_weights(p, x0, x1, x2);
  f = k * min(min(share.x, share.y), share.z) * radius * -normalize(cross(x1 - x0, x2 - x0));
  return true;
}

// A pulling tool's attachment spring: k (target - x).
vec3 pull_attachment(vec3 target, vec3 x, float k) { return k * (target - x); }

// Coulomb friction with a stick anchor (force_law::anchor_friction): f_t =
// k_t P (anchor - x) while |f_t| <= mu_s N (sticking) or mu_k N (slipping),
// else the point slips and the anchor trails it where |f_t| = mu_k N.
// `anchor` (world) and `slipping` are updated in place.
vec3 anchor_friction(vec3 x, vec3 normal_force, float k_t, float mu_s, float mu_k, inout vec3 anchor,
                     inout bool slipping) {
  const float N = length(normal_force);
  if (!(N > 0.0)) {
    anchor = x;
    slipping = false;
    return vec3(0.0);
  }
  const vec3 n = normal_force / N;
  const vec3 d = anchor - x;
  const vec3 tangential = d - dot(d, n) * n;
  const vec3 f = k_t * tangential;
  const float ft = length(f);
  if (ft <= (slipping ? mu_k : mu_s) * N) {
    slipping = false;
    return f;
  }
  slipping = true;
  const float slip = mu_k * N / ft;
  anchor = x + slip * tangential;
  return slip * f;
}
