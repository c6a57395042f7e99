#pragma once
// The immutable Model: topology, rest state, parameters and the gather layout.
// Everything a backend needs to step, sized once at build time. Points are
// stored in the *internal* numbering (locality order, then valence-sorted
// within windows, see layout.h); `input_of_internal` maps back so every output
// is reported in the user's numbering.
#include <array>
#include <vector>

#include "core/mesh/tet_mesh.h"
#include "core/model/layout.h"
#include "core/model/material.h"
#include "core/model/suture.h"
#include "core/util/vec.h"

namespace organsim {

struct Model {
  // Points (internal numbering).
  std::vector<Vec3> rest_position;   // m (npoint)
  std::vector<double> mass;          // lumped mass, kg (npoint)
  std::vector<double> inv_mass;      // 1/mass, 0 for fixed points, 1/kg (npoint)
  std::vector<uint8_t> fixed;        // 1 if the point never moves (npoint)
  // Multiplier of the tool's contact / grasp stiffness, min(1, m / median free
  // mass) (npoint; empty = 1 everywhere): see core/model/stiffness.h.
  std::vector<double> tool_k_scale;
  std::vector<int32_t> input_of_internal;  // user's point id of internal point i (npoint)
  std::vector<int32_t> internal_of_input;  // internal id of user's point i (npoint)

  // Topology versions (see model_rebuild.h). Points are append-only: the
  // mesh's own points keep internal ids 0..mesh_points-1 in every version,
  // and a point appended by a change has internal id == output number >=
  // mesh_points.
  int32_t version = 0;               // 0 as built from the mesh, +1 per topology change
  int32_t mesh_points = 0;           // points read from the mesh
  std::vector<int32_t> origin;       // internal id of the point each point was copied from, itself for mesh points (npoint)

  // Springs: one per unique tet edge (sorted by ends), then one per suture
  // (in the order of `sutures`), ends in internal numbering.
  std::vector<Edge> spring_ends;     // (nspring x 2), ends[0] < ends[1]
  std::vector<double> spring_rest;   // rest length, m (nspring); a suture's when tied (see spring_rest_at)
  std::vector<double> spring_k;      // stiffness, N/m (nspring)
  std::vector<double> spring_d;      // damper, N s/m (nspring)
  // Sutures: springs first_suture().. are these, tension only, rest length
  // on a schedule. Empty for a model no suture event touched.
  std::vector<Suture> sutures;

  // Tetrahedra, positively oriented, internal numbering.
  std::vector<Tet> tet_points;       // (ntet x 4)
  std::vector<double> tet_rest_volume;  // m^3 (ntet)
  // The volume term (Material::volume_formulation) in one of two forms:
  // per tet, energy k_t/2 (V_t - V_t^r)^2 with tet_k; or averaged nodal,
  // energy k_a/2 (V_a - V_a^r)^2 on the nodal volumes V_a = sum of V_t / 4
  // over the tets of a, with point_volume_k. At most one of the two is set.
  std::vector<double> tet_k;         // per-tet K / V_r, N/m^5 (ntet); empty unless the per-tet term is on
  std::vector<double> point_rest_volume;  // nodal rest volume V_a^r, m^3 (npoint; 0 in no tet)
  std::vector<double> point_volume_k;     // nodal K / V_a^r, N/m^5 (npoint); empty unless the nodal term is on
  // The shear element (core/model/shear_element.h), on for nu < 1/4 only,
  // never together with a volume term: per tet a neo-Hookean energy without
  // its lambda part, k_t [(|F|^2 - 3) / 2 - ln det F], k_t = mu_e V_t^r, with
  // the rest gradients g_i of each tet's barycentric coordinates (corners in
  // tet_points order).
  std::vector<double> tet_shear_k;                   // mu_e V_t^r, J (ntet); empty unless the element is on
  std::vector<std::array<Vec3, 4>> tet_shape_gradient;  // g_i, 1/m (ntet x 4); empty unless the element is on
  // The element's node-smoothed share s (Material::shear_formulation): the
  // energy is (1 - s) on each tet's F and s on F averaged over each point's
  // tets, weighted by k_t; point_shear_k holds K_a = sum of k_t over the tets
  // of a, J (npoint). 0 and empty unless the element is on and smoothed.
  double shear_smoothed_share = 0;
  std::vector<double> point_shear_k;
  // Its damper's time constant tau, s (material.spring_damping_time, as the
  // springs' d = tau k): viscous stress 2 mu_e tau D, D the rate of
  // deformation; at rest its damping matrix is tau times the element's
  // stiffness (core/model/shear_element.h). 0 without the element.
  double shear_damping_time = 0;

  // Scene parameters.
  Vec3 gravity{0, 0, 0};             // m/s^2
  double viscous_damping = 0;        // alpha, 1/s
  Material material;                 // as given (the first of `materials` when there are several), for reporting
  // Per-label materials (ModelOptions::label_materials): each tet's material
  // index into `materials`; both empty when one material is used everywhere.
  // Quantities that are one number for the whole model (viscous damping, the
  // shear element's damping time and smoothed share, whether the shear
  // element or a volume term is used, and its form) must agree between them:
  // build_model refuses materials that differ there.
  std::vector<Material> materials;
  std::vector<int32_t> tet_material;  // (ntet) or empty
  std::vector<int32_t> tet_label;     // each tet's mesh label (ntet); empty for an unlabelled mesh

  // The boundary surface (core/mesh/boundary.h: the faces owned by one tet,
  // counter-clockwise seen from outside), re-extracted by every rebuild, and
  // for each point the surface triangles it belongs to, ascending (CSR:
  // those of point p are surface_tri[surface_offset[p] .. surface_offset[p + 1])).
  // The tool's surface contact gathers them (docs/physics.md, "Tool").
  std::vector<Tri> surface;
  std::vector<int32_t> surface_offset;  // (npoint + 1)
  std::vector<int32_t> surface_tri;     // triangle ids (3 nsurface)
  // Per-point gather layout (springs and tets gathered per point, no atomics).
  GatherLayout layout;

  int32_t npoint() const { return static_cast<int32_t>(rest_position.size()); }
  int32_t nspring() const { return static_cast<int32_t>(spring_ends.size()); }
  int32_t nsuture() const { return static_cast<int32_t>(sutures.size()); }
  // Springs [0, first_suture()) are the tissue's (tet edges), sorted by ends.
  int32_t first_suture() const { return nspring() - nsuture(); }
  const Suture& suture_of_spring(int32_t s) const { return sutures[s - first_suture()]; }
  // Rest length of spring s at time t (a suture tightens; the tissue's is fixed), m.
  double spring_rest_at(int32_t s, double t) const {
    return s < first_suture() ? spring_rest[s] : suture_of_spring(s).rest_at(t);
  }
  int32_t ntet() const { return static_cast<int32_t>(tet_points.size()); }
  int32_t nsurface() const { return static_cast<int32_t>(surface.size()); }
  // Surface triangles point p belongs to (0 for an inner point).
  int32_t surface_count(int32_t p) const {
    return surface_offset.empty() ? 0 : surface_offset[p + 1] - surface_offset[p];
  }
  bool has_volume() const { return !tet_k.empty() || !point_volume_k.empty(); }
  bool has_nodal_volume() const { return !point_volume_k.empty(); }
  bool has_shear_element() const { return !tet_shear_k.empty(); }
  bool has_smoothed_shear() const { return shear_smoothed_share > 0; }
  bool has_gravity() const { return gravity.squaredNorm() > 0; }
  double tool_scale(int32_t i) const { return tool_k_scale.empty() ? 1.0 : tool_k_scale[i]; }
  const Material& material_of_tet(int32_t t) const { return tet_material.empty() ? material : materials[tet_material[t]]; }
  double total_mass() const;
  double rest_volume() const;
};

struct ModelOptions {
  Vec3 gravity{0, 0, 0};                    // m/s^2
  std::vector<FixedSelector> fixed;         // fixed-point selectors
  int32_t chunk_size = kDefaultChunkSize;   // C of SELL-C-sigma
  int32_t sort_window = kDefaultSortWindow; // sigma of SELL-C-sigma
  bool reorder_for_locality = true;         // reverse Cuthill-McKee before the valence sort
  // Materials by tet label (scenario `materials`); empty: the one material
  // for every tet. Every label of the mesh must have exactly one.
  std::vector<LabelMaterial> label_materials;
};

// Builds the Model. Throws Error(Input) naming the element for tets with
// non-positive or tiny volume, out-of-range indices, non-finite points, and
// Error(Scenario) for non-positive density or stiffness, and for fixed
// selectors of which one matches no point or which together hold them all.
// `source` names the mesh in error messages.
Model build_model(const TetMesh& mesh, const Material& material, const ModelOptions& options,
                  const std::string& source = "mesh");


// Whether a box, plane or sphere selector matches a rest position x (m);
// false for indices and labels, which select by id.
bool selector_matches(const FixedSelector& s, const Vec3& x);

}  // namespace organsim
