#pragma once
// The validation cases: textbook elasticity problems posed on a tet mesh and
// solved for the Model's small-strain static response (static_solve.h), or
// for the indentation also as a run settles (run_equilibrium.h), each with
// the theory it is compared with. SI units. docs/validation.md shows the
// tables `organsim validate` makes from them.
//
// Theory uses effective_elasticity(material) (core/model/stiffness.h).
// Every case builds its Model from `mesh` and `material` itself (no fixed
// selectors: the case states its supports) and finds faces from the mesh's
// bounding box, so any mesh of the right box works: CGAL meshes in the
// command, small structured ones in the tests.
#include <optional>
#include <string>
#include <vector>

#include "core/mesh/tet_mesh.h"
#include "core/model/material.h"
#include "core/sim/tool.h"

namespace organsim {

// Uniaxial compression of a block along z: bottom face on rollers (u_z = 0,
// one point pinned in x and y, one more in y), top face pressed down by
// `strain` * height on frictionless rollers, sides free. Theory: a uniform
// uniaxial stress, sigma = E strain and lateral strain -nu strain.
struct UniaxialResult {
  double young_modulus = 0;  // measured: mean stress / strain, Pa
  double poisson_ratio = 0;  // measured: -(lateral strain) / (axial strain), mean of x and y
  int32_t points = 0;
};
UniaxialResult uniaxial_compression(const TetMesh& block, const Material& material, double strain = 1e-3);

// A beam along x with its x = min face clamped and a load on its x = max face.
// tip_load: a total force P along -z shared equally by the tip face's points;
// measured stiffness P / (mean tip deflection); theory Euler-Bernoulli
// P L^3 / (3 E I) plus Timoshenko shear P L / (kappa G A).
// guided: the tip face moved rigidly by -delta in z (no rotation); measured
// stiffness (reaction) / delta; theory P L^3 / (12 E I) plus the same shear term.
enum class BeamEnd { TipLoad, Guided };
struct BeamResult {
  double stiffness = 0;                 // measured, N/m
  double euler_bernoulli = 0;           // N/m, bending only
  double timoshenko = 0;                // N/m, bending + shear
  int32_t points = 0;
};
BeamResult cantilever(const TetMesh& beam, const Material& material, BeamEnd end);

// A rigid frictionless sphere of `radius` pressed `depth` into the middle of
// the block's top face (bottom face clamped), for each depth. Contact is a
// stiff penalty, as the tool applies it (`contact`): on the boundary
// triangles the sphere reaches (force_law::sphere_triangle_penalty,
// linearised at each triangle's closest point and normal), or on the points
// it reaches; iterated until the touching set and the closest points settle. Theory: Hertz, F = 4/3 E / (1 - nu^2) sqrt(R) d^1.5
// (a half-space, d << R).
struct IndentationResult {
  std::vector<double> depth;   // m
  std::vector<double> force;   // measured, N
  std::vector<double> hertz;   // N
  std::vector<int32_t> contacts;  // points (or with surface contact, triangles) touching at each depth
  int32_t points = 0;
};
// `hertz_layer`: the surface contact in series with the sub-cell Hertz
// layer (a scenario's tool.hertz_layer; force_law::hertz_layer_offset).
// `as_run`: instead of the small-strain static response (above), the
// equilibrium a run settles into (run_equilibrium.h: the force law at the
// deformed shape, the backends' own contact pass) with a run's penalty,
// `as_run->contact_stiffness` as a scenario's tool.contact_stiffness (N/m
// for a point of the median mass); its compliance is part of the result.
struct AsRun {
  double contact_stiffness = 0;
};
IndentationResult sphere_indentation(const TetMesh& block, const Material& material, double radius,
                                     const std::vector<double>& depths,
                                     ToolContact contact = ToolContact::Surface, bool hertz_layer = false,
                                     std::optional<AsRun> as_run = std::nullopt);

// A line load: a rigid frictionless capsule of `radius` lying along y across
// the middle of the block's top face (bottom face clamped), its axis 2R
// longer than the block on each side so the rounded ends lie beyond it,
// pressed `depth` into the top (0 < depth < radius), for each depth. Contact
// on the boundary triangles (force_law::capsule_triangle_penalty, the
// tool's surface contact), solved as sphere_indentation's; the force is the
// one the clamped base carries (the settled state's K u there), since at
// the kinks where a triangle's closest point jumps between the ends of the
// chord under the axis the penalties are one side's. No closed-form
// theory: a cylinder on an elastic half-space has no finite-depth force
// law (the 2D surface displacement under a line load grows like the log of
// the body's size), so the case is compared with itself on a refined mesh.
struct LineLoadResult {
  std::vector<double> depth;      // m
  std::vector<Vec3> force;        // the tool's force on the tissue as the base carries it, N (a push is along -z)
  std::vector<Vec3> contact_force;  // the force law's penalties summed at the settled state, N
  std::vector<int32_t> contacts;  // triangles touching at each depth
  int32_t points = 0;
  double capsule_length = 0;      // the axis segment, m
};
// With `line_layer` the capsule's surface contact is in series with the
// sub-cell line layer (force_law::HertzLayer), as the backends apply it.
LineLoadResult capsule_line_load(const TetMesh& block, const Material& material, double radius,
                                 const std::vector<double>& depths, bool line_layer = false);

}  // namespace organsim
