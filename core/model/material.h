#pragma once
// Material and scene parameters, SI units. Parsed from the scenario's
// `material` section; defaults are validated in validate_material().
#include <optional>
#include <string>
#include <vector>

#include "core/util/vec.h"

namespace organsim {

// Form of the volume term (docs/physics.md): per tet, energy K/2 (V_t - V_t^r)^2 / V_t^r
// on every tet; or averaged nodal, energy K/2 (V_a - V_a^r)^2 / V_a^r on every
// point's nodal volume V_a = sum of V_t / 4 over its tets (Bonet and Burton
// 1998), which does not lock in bending near nu = 1/2. Both add K to lambda at
// small strain.
enum class VolumeFormulation { PerTet, Nodal };

// Form of the shear element below nu = 1/4 (docs/physics.md): per tet on each
// tet's deformation gradient (a linear tet: too stiff in bending with few
// cells through a part's thickness), or smoothed, half on the per-tet
// gradients and half on gradients averaged over each point's tets (node-based
// smoothed FEM, which alone is too soft; the even blend lands within a few
// per cent of beam theory at 2-3 cells through the thickness).
enum class ShearFormulation { PerTet, Smoothed };

struct Material {
  double density = 1060.0;  // kg/m^3 (soft tissue ~1000-1100)
  // Spring stiffness: from Young's modulus (default) or an explicit constant.
  // k_e = E_s * (sum of rest volumes of the tets sharing edge e) / r_e^2 stores
  // the energy of a linear solid of modulus E_s with Poisson ratio 1/4 (the
  // ratio a tet spring lattice has). See core/model/stiffness.h.
  double young_modulus = 3000.0;                // Pa (liver: a few kPa)
  std::optional<double> spring_stiffness;       // N/m; overrides young_modulus when set
  // With a Poisson ratio (0 <= nu < 0.5) the springs, the volume term (nu >=
  // 1/4) or the shear element (nu < 1/4) are derived from E and nu
  // (core/model/stiffness.h; volume_modulus must then be 0); without one,
  // E_s = young_modulus and volume_modulus are used as given.
  std::optional<double> poisson_ratio;
  double spring_damping_time = 0.002;           // s; damper d_e = spring_damping_time * k_e (N s/m)
  double viscous_damping = 1.0;                 // 1/s; mass-proportional drag F = -alpha m v
  // Volume conservation: energy K/2 (V - V_r)^2 / V_r per tet, i.e. per-tet
  // k_v = K / V_r (N/m^5). 0 switches the volume pass off.
  double volume_modulus = 0.0;                  // Pa
  // Unset: nodal with poisson_ratio, per tet without (existing scenarios keep
  // their forces); see volume_formulation() in core/model/stiffness.h.
  std::optional<VolumeFormulation> volume_formulation;
  ShearFormulation shear_formulation = ShearFormulation::Smoothed;  // used only below nu = 1/4
};

// A material for the tets of some labels (a scenario's `materials` entry).
struct LabelMaterial {
  std::vector<int32_t> labels;  // tet labels (TetMesh::labels) this material is for
  Material material;
};

// One fixed-point selector; a point is fixed when any selector matches it.
struct FixedSelector {
  enum class Kind { Box, Plane, Sphere, Indices, Label } kind = Kind::Indices;
  Vec3 min{0, 0, 0}, max{0, 0, 0};        // Box, m
  Vec3 point{0, 0, 0}, normal{0, 0, 1};   // Plane: points with dot(x - point, normal) >= 0, m
  Vec3 center{0, 0, 0};                   // Sphere centre, m
  double radius = 0;                      // Sphere radius, m
  std::vector<int32_t> indices;           // Indices: input point numbering
  int32_t label = 0;                      // Label: every point of a tet with this label
};

}  // namespace organsim
