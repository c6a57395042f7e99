// The shear element's gathered data, shared by step.comp (SHEAR_ELEMENT) and
// shear_smoothing.comp, included by name after force_law.glsl (whose
// shear_stress both evaluate). GLSL matrices are column-major:
// outerProduct(u, g) is u g^T and F[k] is column k.

// The shear element's parameters of one gathered tet (p, a, b, c); mirrors
// gl::ShearEntry (core/gl/gl_model_pack.h).
struct ShearEntry {
  vec4 ga;  // rest gradient of a's barycentric coordinate (1/m), w = k_t = mu_e V_t^r (J)
  vec4 gb;  // b's, w = d_t = tau k_t, the damper (J s)
  vec4 gc;  // c's, w = k_t / K_p, the tet's weight in p's smoothed gradient (0 unless smoothed)
};

// F - I = sum over the others q of (u_q - u_p) g_q^T, from the displacements
// relative to p (du_q = u_q - u_p, u = x - X): exactly 0 at rest, and free
// of the rounding of absolute positions far from the origin.
mat3 shear_displacement_gradient(vec3 du_a, vec3 du_b, vec3 du_c, ShearEntry g) {
  return outerProduct(du_a, g.ga.xyz) + outerProduct(du_b, g.gb.xyz) + outerProduct(du_c, g.gc.xyz);
}
