#pragma once
// The force law of organsim, written once: each element's force (and, where
// a caller needs it, its energy) as a small function of plain numbers,
// templated on the number type. Every evaluation of the physics calls these:
// the double-precision reference (core/sim/reference_forces.cpp), the
// scatter step in its precision, the energy of
// the blow-up monitor, the shear element's reference and energy, and every
// output that reports a force (the ParaView series' tool force). The
// simd kernel evaluates the same formulas on 1 to 16 lanes and is tested
// against the reference point by point; the GLSL twin of this file is
// shaders/force_law.glsl (step.comp and its companions include it).
// docs/physics.md derives each formula. SI units: m, N, Pa, s.
//
// The functions take no Model: what an element's parameters are (stiffness
// from E and nu, rest lengths and volumes) is the Model's business
// (core/model); how elements are gathered and summed is each backend's.

#include <cmath>
#include <vector>

namespace organsim::force_law {

// --- Springs -----------------------------------------------------------------

// Tension of a spring with its damper, N (positive pulls the ends together):
//   T = k (L - r) + d (v_b - v_a) . u,  u = (x_b - x_a) / L.
// The force on end a is T u, on end b -T u. `closing_rate` is (v_b - v_a) . u
// in m/s (negative while the ends approach).
template <class Real>
inline Real spring_tension(Real k, Real d, Real length, Real rest, Real closing_rate) {
  return k * (length - rest) + d * closing_rate;
}

// A suture is a spring that pulls only: no force while slack (L <= r), and
// its damper never turns the pull into a push. Returns the tension it
// applies given the spring law's `tension`.
template <class Real>
inline Real suture_tension(Real tension, Real length, Real rest) {
  return length > rest && tension > Real(0) ? tension : Real(0);
}

// Elastic energy of a spring, J: k/2 (L - r)^2. A suture stores none while slack.
template <class Real>
inline Real spring_energy(Real k, Real length, Real rest) {
  const Real stretch = length - rest;
  return k * stretch * stretch / 2;
}
template <class Real>
inline Real suture_energy(Real k, Real length, Real rest) {
  return length > rest ? spring_energy(k, length, rest) : Real(0);
}

// --- Volume conservation -------------------------------------------------------

// 6 V of the tet (x0, x1, x2, x3) from its edges e_k = x_k - x0: e1 . (e2 x e3).
template <class V3>
inline auto tet_volume6(const V3& e1, const V3& e2, const V3& e3) {
  return e1.dot(e2.cross(e3));
}

// 6 dV/dx_k for k = 1, 2, 3 (dV/dx_0 = -(sum of the three)):
//   g1 = e2 x e3, g2 = e3 x e1, g3 = e1 x e2.
template <class V3>
inline void tet_volume_gradients6(const V3& e1, const V3& e2, const V3& e3, V3& g1, V3& g2, V3& g3) {
  g1 = e2.cross(e3);
  g2 = e3.cross(e1);
  g3 = e1.cross(e2);
}

// Pressure of a volume term, Pa: p = k (V - V_r). The force on a vertex x_i
// of the volume is -p dV/dx_i (the gradient of E = k/2 (V - V_r)^2). The
// per-tet term uses the tet's k_v, V_t; the averaged nodal term uses each
// point's k_a, V_a (sum of V_t / 4 over its tets) and gives a tet the mean
// of its corners' pressures (tet_pressure_from_nodal).
template <class Real>
inline Real volume_pressure(Real k, Real volume, Real rest_volume) {
  return k * (volume - rest_volume);
}
template <class Real>
inline Real tet_pressure_from_nodal(Real q0, Real q1, Real q2, Real q3) {
  return (q0 + q1 + q2 + q3) / 4;
}
template <class Real>
inline Real volume_energy(Real k, Real volume, Real rest_volume) {
  const Real dv = volume - rest_volume;
  return k * dv * dv / 2;
}

// --- Shear element (nu < 1/4; core/model/shear_element.h derives it) -------

// Where the barrier -ln J hands over to its quadratic extension.
inline constexpr double kShearElementMinJ = 0.5;

// phi(J): -ln J from kShearElementMinJ up, its quadratic Taylor expansion there below.
double shear_barrier(double J);

// phi'(J): -1/J from kShearElementMinJ up, (J - 2 J_min) / J_min^2 below (the
// extension's slope, continuous with its first two derivatives at J_min).
template <class Real>
inline Real shear_barrier_slope(Real J) {
  const Real jm = static_cast<Real>(kShearElementMinJ);
  return J >= jm ? Real(-1) / J : (J - 2 * jm) / (jm * jm);
}

// cof F = J F^-T, column by column: the cross products of F's other columns.
template <class Matrix3>
inline Matrix3 shear_cofactor(const Matrix3& F) {
  Matrix3 c;
  c.col(0) = F.col(1).cross(F.col(2));
  c.col(1) = F.col(2).cross(F.col(0));
  c.col(2) = F.col(0).cross(F.col(1));
  return c;
}

// P(F) = F + phi'(J) cof F, the first Piola-Kirchhoff stress per unit k of
// the element's energy psi(F) = (|F|^2 - 3) / 2 + phi(J).
template <class Matrix3>
inline Matrix3 shear_stress(const Matrix3& F) {
  const Matrix3 cof = shear_cofactor(F);
  return F + shear_barrier_slope(F.col(0).dot(cof.col(0))) * cof;
}

// psi(F) = (|F|^2 - 3) / 2 + phi(J), the element's energy per unit k, J.
template <class Matrix3>
inline double shear_energy_density(const Matrix3& F) {
  return (static_cast<double>(F.squaredNorm()) - 3) / 2 + shear_barrier(static_cast<double>(F.determinant()));
}

// The damper's stress per unit k for the rate dF/dt = Fdot (Kelvin-Voigt,
// tau the damping time): (2 tau / J_d) sym(Fdot cof^T) cof, J_d = max(J, J_min).
template <class Matrix3, class Real>
inline Matrix3 shear_damping_stress(const Matrix3& Fdot, const Matrix3& cof, Real J, Real tau) {
  const Real jd = J > static_cast<Real>(kShearElementMinJ) ? J : static_cast<Real>(kShearElementMinJ);
  const Matrix3 a = Fdot * cof.transpose();
  return (tau / jd) * (a + a.transpose()) * cof;
}

// --- Rest stiffness -----------------------------------------------------------
// The linearisation of the laws above at rest, as 3 x 3 blocks K_ij =
// -df_i/dx_j: what the static solve assembles, the Gershgorin bound sums and
// dt_crit's operator applies. At rest the stretch, volume change and strain
// are zero, so only these (Gauss-Newton) parts remain.

// A spring along the unit vector u: K_aa = K_bb = k u u^T, K_ab = K_ba = -k u u^T.
template <class V3, class Real>
inline auto spring_rest_stiffness(Real k, const V3& u) {
  return (k * u * u.transpose()).eval();
}

// The volume term of a tet or a node with stiffness k (per volume squared)
// and volume gradients g_i, g_j: K_ij = k g_i g_j^T.
template <class V3, class Real>
inline auto volume_rest_stiffness(Real k, const V3& gi, const V3& gj) {
  return (k * gi * gj.transpose()).eval();
}

// The shear element per unit k with shape gradients g_i, g_j:
// K_ij = (g_i . g_j) I + g_j g_i^T (shear_stress linearised at F = I).
template <class V3>
inline auto shear_rest_stiffness(const V3& gi, const V3& gj) {
  using M = decltype((gj * gi.transpose()).eval());
  return (gi.dot(gj) * M::Identity() + gj * gi.transpose()).eval();
}

// --- Tangent stiffness (implicit integration) ----------------------------------
// What the implicit integrator's linear system holds away from rest
// (core/sim/implicit_system.h), kept positive semi-definite so that its
// conjugate gradients converge: K = -df/dx, D = -df/dv.

// A spring of length L along u with tension T (its damper's included):
// K_aa = (k - t) u u^T + t I with t = max(T, 0) / L, the transverse term of
// a stretched spring. A compressed spring's transverse term -|T|/L (the
// stiffness that lets it buckle sideways) is left out, the usual choice
// (Choi and Ko 2002): it would make the system indefinite. Its damper gives
// D_aa = d u u^T (the damper's dependence on the direction u is left out).
// Returns t.
template <class Real>
inline Real spring_transverse_stiffness(Real tension, Real length) {
  return tension > Real(0) && length > Real(0) ? tension / length : Real(0);
}

// A penalty f = k (R - d) n (push_penalty, sphere_triangle_penalty and the
// capsule's): K = k n n^T along the normal. Its tangential part
// -k (R - d)/d (I - n n^T) (a point sliding round the sphere feels less
// push) is left out for the same reason.
template <class V3, class Real>
inline auto penalty_normal_stiffness(Real k, const V3& n) {
  return (k * n * n.transpose()).eval();
}

// --- Tool ---------------------------------------------------------------------

// Push contact of a sphere (radius R, penalty k N/m, the point's stiffness
// share s): a point at `offset` = x - c from the centre with |offset| < R
// (for a capsule, c is the segment's point closest to x,
// segment_closest_point)
// gets f = k s (R - |offset|) offset / |offset| (along +z at the exact
// centre, where the direction is undefined). Returns false, f untouched,
// for a point outside the sphere.
template <class V3, class Real>
inline bool push_penalty(const V3& offset, Real radius, Real k, V3& f) {
  const Real dist = offset.norm();
  if (!(dist < radius)) return false;
  const V3 n = dist > Real(0) ? V3(offset / dist) : V3(Real(0), Real(0), Real(1));
  f = k * (radius - dist) * n;
  return true;
}
template <class Real>
inline Real push_penalty_energy(Real k, Real radius, Real dist) {
  return dist < radius ? k * (radius - dist) * (radius - dist) / 2 : Real(0);
}

// Closest point of the triangle (a, b, c) to p as barycentric weights w
// (q = w0 a + w1 b + w2 c, each in [0, 1], summing to 1), by the triangle's
// Voronoi regions (vertex, edge, face; Ericson, Real-Time Collision
// Detection 5.1.5). The weights are continuous in p, so anything spread by
// them is continuous as p crosses an edge or a vertex. A degenerate edge
// falls to its first end.
template <class V3, class Real>
inline void triangle_closest_weights(const V3& p, const V3& a, const V3& b, const V3& c, Real w[3]) {
  auto set = [&](Real w0, Real w1, Real w2) { w[0] = w0, w[1] = w1, w[2] = w2; };
  const V3 ab = b - a, ac = c - a, ap = p - a;
  const Real d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= Real(0) && d2 <= Real(0)) return set(1, 0, 0);
  const V3 bp = p - b;
  const Real d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= Real(0) && d4 <= d3) return set(0, 1, 0);
  const Real vc = d1 * d4 - d3 * d2;
  if (vc <= Real(0) && d1 >= Real(0) && d3 <= Real(0)) {
    const Real v = d1 - d3 > Real(0) ? d1 / (d1 - d3) : Real(0);
    return set(1 - v, v, 0);
  }
  const V3 cp = p - c;
  const Real d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= Real(0) && d5 <= d6) return set(0, 0, 1);
  const Real vb = d5 * d2 - d1 * d6;
  if (vb <= Real(0) && d2 >= Real(0) && d6 <= Real(0)) {
    const Real v = d2 - d6 > Real(0) ? d2 / (d2 - d6) : Real(0);
    return set(1 - v, 0, v);
  }
  const Real va = d3 * d6 - d5 * d4;
  if (va <= Real(0) && d4 - d3 >= Real(0) && d5 - d6 >= Real(0)) {
    const Real den = (d4 - d3) + (d5 - d6);
    const Real v = den > Real(0) ? (d4 - d3) / den : Real(0);
    return set(0, 1 - v, v);
  }
  const Real sum = va + vb + vc;
  if (!(sum > Real(0))) return set(1, 0, 0);  // a flat triangle outside every edge region
  const Real v = vb / sum, u = vc / sum;
  return set(1 - v - u, v, u);
}

// The surface contact's stiffness factor of a triangle: the smallest of its
// corners' shares (sphere_triangle_penalty says why).
template <class Real>
inline Real triangle_penalty_scale(const Real share[3]) {
  const Real a = share[0] < share[1] ? share[0] : share[1];
  return a < share[2] ? a : share[2];
}

// Surface contact of a sphere (centre c, radius R, penalty k N/m) with one
// boundary triangle (x0, x1, x2, counter-clockwise seen from outside): the
// penalty acts at the triangle's closest point q = sum w_i x_i,
//   f = k_t (R - |q - c|) n,  n = (q - c) / |q - c|
// (the inward normal when c lies on the triangle), and corner i receives
// w_i f, so the total is f and the torque about c is (q - c) x f. Its
// stiffness k_t = k min_i share_i with share_i = s_i / n_i (s_i the point's
// stiffness share, Model::tool_k_scale; n_i its number of surface
// triangles) keeps every point's contact stiffness, the sum over its
// triangles of w_i^2 k_t, at most k s_i: the bound dt_crit counts, the same
// as the point penalty's; a vertex pressed by all its triangles feels up to
// k s_i, as with point contact. k_t is a constant of the triangle, so the
// force is minus the gradient of k_t/2 (R - |q - c|)^2 (the distance to a
// triangle has the gradient w_i n in its corner i): the contact stores and
// returns energy and cannot pump it into the tissue (a k_t that followed
// the weights did, by its missing gradient term). Returns false (f, w
// untouched) when the triangle is outside the sphere.
template <class V3, class Real>
inline bool sphere_triangle_penalty(const V3& center, Real radius, const V3& x0, const V3& x1, const V3& x2, Real k,
                                    const Real share[3], V3& f, Real w[3]) {
  Real wt[3];
  triangle_closest_weights(center, x0, x1, x2, wt);
  const V3 q = wt[0] * x0 + wt[1] * x1 + wt[2] * x2;
  const V3 offset = q - center;
  const Real dist = offset.norm();
  if (!(dist < radius)) return false;
  V3 n;
  if (dist > Real(0)) {
    n = offset / dist;
  } else {
    const V3 outward = (x1 - x0).cross(x2 - x0);
    const Real len = outward.norm();
    n = len > Real(0) ? V3(-outward / len) : V3(Real(0), Real(0), Real(-1));
  }
  f = k * triangle_penalty_scale(share) * (radius - dist) * n;
  for (int i = 0; i < 3; ++i) w[i] = wt[i];
  return true;
}

// The push penalty's derivative with respect to the tool centre c, for the
// haptic local force model (the tool's local contact stiffness). The penalty
// f = k (R - d) n, n = o / d, o = q - c, d = |o| < R (push_penalty with k =
// k s; sphere_triangle_penalty with k = k_t), acts on a contact point q that
// follows c as dq/dc = P: P = 0 for a mesh point with the tissue held, the
// projector onto the closest feature's directions for a triangle's closest
// point (face: I - m m^T, m its normal; edge: e e^T; vertex: 0). With
// df/do = k (-n n^T + (R - d)/d (I - n n^T)):
//   df/dc = df/do (P - I).
// At d = 0 (n chosen, not defined) only the normal term -k n n^T is kept.
// The tool's reaction F = -sum f then has dF/dc = -sum df/dc (N/m). No
// GLSL twin: it is evaluated once per tick on the CPU from the backend's
// positions (core/sim/contact_stiffness.h), whichever backend stepped.
template <class M3, class V3, class Real>
inline M3 push_penalty_center_jacobian(const V3& n, Real dist, Real radius, Real k, const M3& follow) {
  const M3 nn = n * n.transpose();
  M3 df_do = -nn;
  if (dist > Real(0)) df_do += (radius - dist) / dist * (M3::Identity() - nn);
  return k * df_do * (follow - M3::Identity());
}

// --- Capsule tool -------------------------------------------------------------
// A capsule is the set of points within R of the segment a-b in the world
// (the tool frame's end points placed by its pose); a sphere is the capsule
// whose segment has zero length (a == b == its centre).

// The point of the segment a-b closest to p: a + s (b - a), s clamped to
// [0, 1]; exactly a when a == b, so a sphere's offsets are those of its
// centre bit for bit.
template <class V3>
inline V3 segment_closest_point(const V3& p, const V3& a, const V3& b) {
  using Real = typename V3::Scalar;
  const V3 ab = b - a;
  const Real len2 = ab.dot(ab);
  if (!(len2 > Real(0))) return a;
  Real s = ab.dot(V3(p - a)) / len2;
  s = s < Real(0) ? Real(0) : s > Real(1) ? Real(1) : s;
  return a + s * ab;
}

// Where along the segment a-b its point closest to p lies: |b - a| s with s
// as in segment_closest_point, m (0 when a == b): a touch's place along a
// capsule's axis for the layer (HertzLayer::add).
template <class V3>
inline typename V3::Scalar segment_axial_position(const V3& p, const V3& a, const V3& b) {
  using Real = typename V3::Scalar;
  const V3 ab = b - a;
  const Real len2 = ab.dot(ab);
  if (!(len2 > Real(0))) return Real(0);
  Real s = ab.dot(V3(p - a)) / len2;
  s = s < Real(0) ? Real(0) : s > Real(1) ? Real(1) : s;
  return s * std::sqrt(len2);
}

// The closest points of the segments p1-q1 and p2-q2 as parameters s, t in
// [0, 1] (Ericson, Real-Time Collision Detection 5.1.9; parallel segments
// take s = 0, a degenerate segment its first end).
template <class V3, class Real>
inline void segments_closest(const V3& p1, const V3& q1, const V3& p2, const V3& q2, Real& s, Real& t) {
  auto clamp01 = [](Real v) { return v < Real(0) ? Real(0) : v > Real(1) ? Real(1) : v; };
  const V3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const Real a = d1.dot(d1), e = d2.dot(d2), f = d2.dot(r);
  if (!(a > Real(0))) {
    s = 0;
    t = e > Real(0) ? clamp01(f / e) : Real(0);
    return;
  }
  const Real c = d1.dot(r);
  if (!(e > Real(0))) {
    t = 0;
    s = clamp01(-c / a);
    return;
  }
  const Real b = d1.dot(d2), denom = a * e - b * b;
  s = denom > Real(0) ? clamp01((b * f - c * e) / denom) : Real(0);
  t = (b * s + f) / e;
  if (t < Real(0)) {
    t = 0;
    s = clamp01(-c / a);
  } else if (t > Real(1)) {
    t = 1;
    s = clamp01((b - c) / a);
  }
}

// The point of the segment a-b (a != b) closest to the triangle (x0, x1,
// x2), with `crossing` set when the segment passes through the triangle
// (the point then lies on it). Otherwise the closest pair joins an end of
// the segment to the triangle or the segment to one of its edges: the
// nearest of those five candidates, the first one on a tie (ends a, b, then
// edges x0-x1, x1-x2, x2-x0). Where the segment runs parallel to the
// triangle the closest points are not unique and the chosen one can jump
// along it as the tie flips (docs/physics.md, the capsule's limits).
template <class V3>
inline V3 segment_point_closest_to_triangle(const V3& a, const V3& b, const V3& x0, const V3& x1, const V3& x2,
                                            bool& crossing) {
  using Real = typename V3::Scalar;
  crossing = false;
  const V3 outward = (x1 - x0).cross(x2 - x0);
  const Real da = outward.dot(V3(a - x0)), db = outward.dot(V3(b - x0));
  if ((da <= Real(0) && db >= Real(0)) || (da >= Real(0) && db <= Real(0))) {
    if (da != db) {
      const V3 p = a + (da / (da - db)) * V3(b - a);
      if (outward.dot(V3((x1 - x0).cross(p - x0))) >= Real(0) && outward.dot(V3((x2 - x1).cross(p - x1))) >= Real(0) &&
          outward.dot(V3((x0 - x2).cross(p - x2))) >= Real(0)) {
        crossing = true;
        return p;
      }
    }
  }
  auto to_triangle2 = [&](const V3& p) {
    Real w[3];
    triangle_closest_weights(p, x0, x1, x2, w);
    return V3(w[0] * x0 + w[1] * x1 + w[2] * x2 - p).squaredNorm();
  };
  V3 best = a;
  Real best2 = to_triangle2(a);
  const Real b2 = to_triangle2(b);
  if (b2 < best2) best = b, best2 = b2;
  const V3* corner[3] = {&x0, &x1, &x2};
  for (int e = 0; e < 3; ++e) {
    const V3& u = *corner[e];
    const V3& v = *corner[(e + 1) % 3];
    Real s, t;
    segments_closest(a, b, u, v, s, t);
    const V3 ps = a + s * V3(b - a);
    const Real d2 = V3(u + t * V3(v - u) - ps).squaredNorm();
    if (d2 < best2) best = ps, best2 = d2;
  }
  return best;
}

// Surface contact of a capsule (segment a-b, radius R) with one boundary
// triangle: the sphere's contact (sphere_triangle_penalty) centred at the
// segment's point closest to the triangle, so the penalty k_t (R - dist)
// acts at the triangle's closest point along the separating direction and
// is spread to the corners by the same weights and the same k_t (the
// per-point stiffness bound dt_crit counts holds as for the sphere). A
// segment through the triangle (its axis inside the tissue) pushes along
// the inward normal with k_t R, the sphere's rule for a centre on the
// triangle. a == b is the sphere itself, bit for bit.
template <class V3, class Real>
inline bool capsule_triangle_penalty(const V3& a, const V3& b, Real radius, const V3& x0, const V3& x1, const V3& x2,
                                     Real k, const Real share[3], V3& f, Real w[3]) {
  if (a == b) return sphere_triangle_penalty(a, radius, x0, x1, x2, k, share, f, w);
  bool crossing = false;
  const V3 p = segment_point_closest_to_triangle(a, b, x0, x1, x2, crossing);
  if (!crossing) return sphere_triangle_penalty(p, radius, x0, x1, x2, k, share, f, w);
  triangle_closest_weights(p, x0, x1, x2, w);
  const V3 outward = (x1 - x0).cross(x2 - x0);
  f = k * triangle_penalty_scale(share) * radius * V3(-outward / outward.norm());
  return true;
}

// --- Sub-cell Hertz layer (a sphere's surface contact) -------------------------
// A linear triangle under a sphere whose contact is narrower than a cell
// moves like a flat punch about one vertex ring wide, so the contact is too
// stiff (a punch's force grows with d, a sphere's with d^(3/2)). The layer
// is the compliance the cells cannot resolve, carried by the tool, in
// series with the surface contact: the tissue sees the sphere moved back
// along its reaction by
//   delta(F) = a^2 / R - F / (2 E* a_h),  a = (3 F R / (4 E*))^(1/3)   while a < a_h,
//   delta(F) = a_h^2 / (3 R)                                            beyond,
// the Hertz indentation of a sphere (radius R, effective modulus E* =
// E / (1 - nu^2)) less that of a flat punch of radius a_h (the cells'
// own), constant once the Hertz contact radius a reaches a_h (there the
// cells resolve the contact). delta(0) = 0, and delta rises with F with a
// continuous slope (zero at a = a_h). A sphere with R / 2 < a_h (a probe)
// stops at a = R / 2 instead, its value there held beyond
// (kLayerContactLimit): Hertz takes the sphere for a paraboloid, within 7 %
// of its depth up to a = R / 2 and 100 % off at a = R, and a probe pressed
// deeper than that becomes a punch of radius about R whose further
// compliance the layer does not carry (it would need an offset beyond what
// a penalty on a triangle can hold: docs/physics.md, the limits). a_h = kHertzLayerPunchFactor x the
// touched triangles' punch radius sqrt(vertex-ring area / pi) (core/model/
// contact_layer.h); the factor is fitted to one validation row (docs/
// validation.md: Hertz at 8 mm cells, d/R 0.1, nu 0.45) and validated on
// the others.
inline constexpr double kHertzLayerPunchFactor = 0.8;
// The largest contact radius (half-width for the line law) the laws are
// followed to, as a share of the tool's radius R.
inline constexpr double kLayerContactLimit = 0.5;

// delta(F), m; 0 for F <= 0.
double hertz_layer_offset(double force, double e_star, double radius, double punch_radius);

// delta in terms of the Hertz radius a <= min(a_h, R / 2) (F = 4 E* a^3 / (3 R)):
// a^2 / R - 2 a^3 / (3 R a_h), E* cancelling; what the solves iterate on.
template <class Real>
inline Real hertz_layer_offset_at(Real a, Real radius, Real punch_radius) {
  return a * a / radius - Real(2) * a * a * a / (Real(3) * radius * punch_radius);
}

// A touching penalty of size m (N), stiffness k (N/m) and direction cosine c
// with the contact's total, with the sphere moved back by delta (m): its
// factor max(0, m - k c delta) / m (0 for m = 0).
template <class Real>
inline Real hertz_layer_factor(Real m, Real k, Real c, Real delta) {
  if (!(m > Real(0))) return Real(0);
  const Real lowered = m - k * c * delta;
  return lowered > Real(0) ? lowered / m : Real(0);
}

// --- Sub-cell line layer (a capsule's shaft lying on the surface) --------------
// The same idea in two dimensions, for a capsule whose shaft touches the
// surface along a length L: a cylinder (radius R) pressed by P = F / L per
// metre has Hertz's contact half-width b = sqrt(4 P R / (pi E*)), and the
// cells, which cannot resolve a strip narrower than themselves, press like
// a flat strip punch of half-width c. In 2D a half-plane's indentation
// grows with the logarithm of the body's size, but the cylinder's less the
// punch's under the same P does not (both against the same far point; the
// log terms cancel):
//   delta(P) = (b^2 / (2 R)) (ln(c / b) + 1/2)   while b < c,
//   delta(P) = c^2 / (4 R)                       beyond,
// continuous with a zero slope where b reaches c, and rising with P below;
// as for the sphere, b stops at R / 2 when R / 2 < c (kLayerContactLimit).
// c = kLineLayerHalfWidthFactor x the touched triangles' punch radius
// sqrt(vertex-ring area / pi); the factor is fitted to one validation row
// (docs/validation.md: the line load at 8 mm cells, d 2 mm, nu 0.45) and
// validated on the others.
inline constexpr double kLineLayerHalfWidthFactor = 0.5;

// delta(P), m; 0 for P <= 0. P in N/m.
double line_layer_offset(double force_per_length, double e_star, double radius, double half_width);

// The layer over a tool's touching triangles, in series with their
// penalties. Moving the tool back by delta along n (the direction of their
// sum F_lin) lowers triangle t's penalty m_t = |f_t| by k_t c_t delta,
// c_t = n_t . n, and never below zero; the force along n is then
//   G(delta) = sum_t c_t max(0, m_t - k_t c_t delta),
// continuous and falling in delta, so F = G(delta(F)) has one root in
// [0, |F_lin|]. solve() finds it, and each penalty is then multiplied by
// factor(i) = max(0, m_t - k_t c_t delta) / m_t: the contact with the tool
// moved back by delta, without state and without an estimate of the
// tissue's stiffness. A triangle that enters the contact at zero depth adds
// nothing. a_h (times kHertzLayerPunchFactor), c and E* are the triangles'
// values weighted by m_t, so they move continuously as the tool slides from
// one triangle to the next.
//
// delta(F) is the sphere's law (hertz_layer_offset) for a contact at a
// point and the line law (line_layer_offset, P = F / L) for a capsule's
// shaft lying along the surface:
//   delta(F) = (1 - beta) delta_sphere(F) + beta delta_line(F / L),
//   beta = min(1, L / (2 a_h)),
// L = sqrt(12 var(s)) with s_t each touch's place along the tool's axis
// (the parameter of the segment's point closest to it, in m; 0 for a
// sphere), weighted by each touch's force along n, max(0, f_t . n) (a
// shaft's touches on the side walls of the hole a probe pressed in push
// across n and carry no length): the length of a uniform line load with
// the same spread. A
// sphere or a capsule pressed on its rounded end has L = 0 (the sphere's
// law, solved as before); a shaft along the surface longer than the
// cells' punch diameter has the line law alone; in between (a tilted
// capsule) the two blend, continuously in the tool's pose.
class HertzLayer {
 public:
  void clear() {
    touches_.clear();
    weight_ = punch_ = e_star_ = delta_ = 0;
  }
  // Triangle penalty f_t with its stiffness k_t, punch radius and E*, in the
  // order the backend visits them; `along` is its place along the tool's
  // axis (m; 0 for a sphere).
  template <class Real>
  void add(const Real f[3], double k_t, double punch_radius, double triangle_e_star, double along = 0) {
    const double f_double[3] = {double(f[0]), double(f[1]), double(f[2])};
    add_touch(f_double, k_t, punch_radius, triangle_e_star, along);
  }
  // Finds delta for a tool of radius R.
  void solve(double radius);
  // The i-th added penalty's factor (1 before solve or with nothing touching).
  // Out of line: one compiled copy, so every caller gets the same bits
  // (m - k c delta cancels where the layer nearly lifts a penalty off).
  double factor(size_t i) const;
  double offset() const { return delta_; }  // m
  bool touching() const { return weight_ > 0; }
  double punch_radius() const { return kHertzLayerPunchFactor * punch_ / weight_; }     // a_h, m
  double line_half_width() const { return kLineLayerHalfWidthFactor * punch_ / weight_; }  // c, m
  double e_star() const { return e_star_ / weight_; }                                  // Pa
  double contact_length() const;                                                        // L, m
  double line_share() const;                                                            // beta
  // delta(F) for a tool of radius R over the touches added, m.
  double offset_for(double force, double radius) const;
  void reserve(size_t n) { touches_.reserve(n); }

 private:
  struct Touch {
    double f[3];
    double m = 0, k = 0, c = 1;
    double s = 0;  // place along the axis, m
  };
  double force_along(double delta) const;     // G(delta)
  double stiffness_along(double delta) const;  // -G'(delta): sum over active t of k_t c_t^2
  // Out of line, as factor(): |f_t| computed in one place, the same bits for
  // every caller.
  void add_touch(const double f[3], double k_t, double punch_radius, double triangle_e_star, double along);
  double linear_direction(double n[3]) const;  // n and |F_lin| (0: n undefined)
  double measure_cosines();                    // every c_t = n_t . n; returns |F_lin|
  double share_of(double length) const;  // beta for a contact length L
  // delta(F) with the length L and share beta already measured.
  double offset_at(double force, double radius, double length, double beta) const;
  void solve_sphere(double radius);  // beta = 0: Newton's steps on the Hertz radius
  std::vector<Touch> touches_;
  double weight_ = 0, punch_ = 0, e_star_ = 0, delta_ = 0;
};

// A pulling tool's attachment spring: f = k s (target - x), target = c + o
// (the point's offset from the centre at grasp time).
template <class V3, class Real>
inline V3 pull_attachment(const V3& target, const V3& x, Real k) {
  return k * (target - x);
}

// --- Friction ----------------------------------------------------------------
// Coulomb friction of a point in contact, regularised by a stick anchor so
// that the step stays explicit. The anchor is where the point stuck to the
// tool (kept in the tool's frame by the caller, so it moves with the tool);
// a tangential spring k_t pulls the point toward it:
//   f_t = k_t P (anchor - x),  P = I - n n^T,  n = f_n / N, N = |f_n|
// (f_n the contact's normal force on the point). A sticking point holds
// while |f_t| <= mu_s N; beyond, it slips. A slipping point keeps slipping
// while |f_t| would exceed mu_k N, and sticks again once it would not (the
// tool stopped or turned back). While it slips the anchor is moved along the
// tangent to x + (mu_k N / |f_t|) P (anchor - x), so that |f_t| = mu_k N: it
// trails the point. A point without normal force has no friction; its
// anchor is put where it is and it sticks. A velocity-clamped law (f_t
// against v_t, at most mu N) would only cancel the velocity already there
// and let a steadily pulled point creep by about F dt / m per step; the
// anchor holds it. Returns f_t; `anchor` (world, m) and `slipping` are the
// point's state, updated in place.
template <class V3, class Real>
inline V3 anchor_friction(const V3& x, const V3& normal_force, Real k_t, Real mu_s, Real mu_k, V3& anchor,
                          bool& slipping) {
  const Real N = normal_force.norm();
  if (!(N > Real(0))) {
    anchor = x;
    slipping = false;
    return Real(0) * normal_force;
  }
  const V3 n = normal_force / N;
  const V3 d = anchor - x;
  const V3 tangential = d - d.dot(n) * n;
  const V3 f = k_t * tangential;
  const Real ft = f.norm();
  if (ft <= (slipping ? mu_k : mu_s) * N) {
    slipping = false;
    return f;
  }
  slipping = true;
  const Real slip = mu_k * N / ft;
  anchor = x + slip * tangential;
  return slip * f;
}

}  // namespace organsim::force_law
