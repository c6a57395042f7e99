// The shear element's formulas shared by step.comp (SHEAR_ELEMENT) and
// shear_smoothing.comp, included by name (core/gl/shader_sources.cpp), so the
// per-tet and the node-smoothed stress cannot drift apart. Same formulas as
// core/model/shear_element.{h,cpp}. GLSL matrices are column-major:
// outerProduct(u, g) is u g^T and F[k] is column k.

// The shear element's parameters of one gathered tet (p, a, b, c); mirrors
// gl::ShearEntry (core/gl/gl_model_pack.h).
struct ShearEntry {
  vec4 ga;  // rest gradient of a's barycentric coordinate (1/m), w = k_t = mu_e V_t^r (J)
  vec4 gb;  // b's, w = d_t = tau k_t, the damper (J s)
  vec4 gc;  // c's, w = k_t / K_p, the tet's weight in p's smoothed gradient (0 unless smoothed)
};

// Where the barrier -ln J hands over to its quadratic extension (kShearElementMinJ).
const float kShearMinJ = 0.5;

// F - I = sum over the others q of (u_q - u_p) g_q^T, from the displacements
// relative to p (du_q = u_q - u_p, u = x - X): exactly 0 at rest, and free
// of the rounding of absolute positions far from the origin.
mat3 shear_displacement_gradient(vec3 du_a, vec3 du_b, vec3 du_c, ShearEntry g) {
  return outerProduct(du_a, g.ga.xyz) + outerProduct(du_b, g.gb.xyz) + outerProduct(du_c, g.gc.xyz);
}

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
