#include "core/model/model.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <set>
#include <string>

#include "core/mesh/boundary.h"
#include "core/model/label_materials.h"
#include "core/model/layout_build.h"
#include "core/model/model_assembly.h"
#include "core/model/ordering.h"
#include "core/model/shear_element.h"
#include "core/model/stiffness.h"
#include "core/model/tet_edges.h"
#include "core/util/error.h"
#include "core/util/format.h"

namespace organsim {

namespace {

// `at` names the material in messages: "material" or "materials[1]".
void validate_material(const Material& m, const std::string& at = "material") {
  auto positive = [&](double v, const char* field, const char* unit) {
    if (!(v > 0) || !std::isfinite(v))
      throw Error(ErrorKind::Scenario, at + "." + field + ": expected a positive number (" + unit + "), got " +
                                           std::to_string(v));
  };
  auto non_negative = [&](double v, const char* field, const char* unit) {
    if (!(v >= 0) || !std::isfinite(v))
      throw Error(ErrorKind::Scenario, at + "." + field + ": expected a number >= 0 (" + unit + "), got " +
                                           std::to_string(v));
  };
  positive(m.density, "density", "kg/m^3");
  if (m.spring_stiffness)
    positive(*m.spring_stiffness, "spring_stiffness", "N/m");
  else
    positive(m.young_modulus, "young_modulus", "Pa");
  non_negative(m.spring_damping_time, "spring_damping_time", "s");
  non_negative(m.viscous_damping, "viscous_damping", "1/s");
  non_negative(m.volume_modulus, "volume_modulus", "Pa");
  if (m.poisson_ratio) {
    const double nu = *m.poisson_ratio;
    if (!(nu >= kMinPoissonRatio && nu < 0.5))
      throw Error(ErrorKind::Scenario, at + ".poisson_ratio: expected a number in [0, 0.5), got " + std::to_string(nu));
    if (m.spring_stiffness)
      throw Error(ErrorKind::Scenario, at + ".poisson_ratio: needs young_modulus, not spring_stiffness");
    // The volume term is derived from nu (core/model/stiffness.h).
    if (m.volume_modulus > 0) throw Error(ErrorKind::Scenario, at + ": give poisson_ratio or volume_modulus, not both");
  }
}

// Per-label materials share what the Model holds as one number (model.h):
// refuse a set that differs there, naming the first two that differ.
void check_materials_agree(const std::vector<LabelMaterial>& materials) {
  const auto refuse = [&](size_t i, const std::string& what) {
    throw Error(ErrorKind::Scenario, "materials[" + std::to_string(i) + "]: " + what + " differs from materials[0]'s; " +
                                         "it is one value for the whole model (docs/scenarios.md, per-label materials)");
  };
  const Material& first = materials.front().material;
  const bool shear = shear_element_modulus(first) > 0;
  for (size_t i = 0; i < materials.size(); ++i) {
    const Material& m = materials[i].material;
    if (m.spring_stiffness && materials.size() > 1) {
      throw Error(ErrorKind::Scenario, "materials[" + std::to_string(i) +
                                           "].spring_stiffness: per-label materials need young_modulus (a spring on an "
                                           "interface takes its stiffness from the tets on each side)");
    }
    if (m.viscous_damping != first.viscous_damping) refuse(i, "viscous_damping");
    if ((shear_element_modulus(m) > 0) != shear) {
      refuse(i, "the side of poisson_ratio 0.25 (below: shear element, at or above: volume term)");
    }
    if (shear && m.spring_damping_time != first.spring_damping_time) refuse(i, "spring_damping_time (with the shear element)");
    if (shear && m.shear_formulation != first.shear_formulation) refuse(i, "shear_formulation");
    if (!shear && volume_formulation(m) != volume_formulation(first) && volume_term_modulus(m) > 0 &&
        volume_term_modulus(first) > 0) {
      refuse(i, "volume_formulation");
    }
  }
}

// Each tet's index into `materials` by its label; Error(Scenario) for a
// label without one (or with two), or a mesh without labels.
std::vector<int32_t> tet_materials(const std::vector<int32_t>& labels, const std::vector<LabelMaterial>& materials,
                                   const std::string& source) {
  if (labels.empty()) {
    throw Error(ErrorKind::Scenario, "materials: per-label materials need a labelled mesh, and " + source +
                                         " has no tet labels (mesh a labelled image, or give one `material`)");
  }
  std::map<int32_t, int32_t> of_label;
  for (size_t i = 0; i < materials.size(); ++i) {
    for (int32_t l : materials[i].labels) {
      if (!of_label.emplace(l, static_cast<int32_t>(i)).second) {
        throw Error(ErrorKind::Scenario, "materials[" + std::to_string(i) + "].labels: label " + std::to_string(l) +
                                             " already has materials[" + std::to_string(of_label[l]) + "]");
      }
    }
  }
  std::vector<int32_t> index(labels.size());
  for (size_t t = 0; t < labels.size(); ++t) {
    const auto it = of_label.find(labels[t]);
    if (it == of_label.end()) {
      std::set<int32_t> present(labels.begin(), labels.end());
      std::string list;
      for (int32_t l : present) list += (list.empty() ? "" : ", ") + std::to_string(l);
      throw Error(ErrorKind::Scenario, "materials: no entry for label " + std::to_string(labels[t]) + " (tet " +
                                           std::to_string(t) + " of " + source + "); the mesh has labels " + list);
    }
    index[t] = it->second;
  }
  return index;
}

std::string no_point_selected(const TetMesh& mesh, const FixedSelector& s, size_t k) {
  static const char* const kinds[] = {"box", "plane", "sphere", "indices", "label"};
  Eigen::AlignedBox3d box;
  for (const Vec3& x : mesh.points) box.extend(x);
  const auto span = [](double lo, double hi) { return format_number(lo) + " .. " + format_number(hi); };
  return "fixed[" + std::to_string(k) + "]." + kinds[static_cast<int>(s.kind)] +
         ": matches no point of the mesh, which spans x " + span(box.min().x(), box.max().x()) + ", y " +
         span(box.min().y(), box.max().y()) + ", z " + span(box.min().z(), box.max().z()) +
         " m (check the selector against the mesh's units and placement)";
}


std::vector<uint8_t> select_fixed(const TetMesh& mesh, const std::vector<FixedSelector>& selectors) {
  const int32_t n = static_cast<int32_t>(mesh.points.size());
  std::vector<uint8_t> fixed(n, 0);
  for (size_t k = 0; k < selectors.size(); ++k) {
    const FixedSelector& s = selectors[k];
    if (s.kind == FixedSelector::Kind::Indices) {
      for (size_t j = 0; j < s.indices.size(); ++j) {
        const int32_t id = s.indices[j];
        if (id < 0 || id >= n)
          throw Error(ErrorKind::Scenario, "fixed[" + std::to_string(k) + "].indices[" + std::to_string(j) +
                                               "]: point " + std::to_string(id) + " out of range 0.." +
                                               std::to_string(n - 1));
        fixed[id] = 1;
      }
      continue;
    }
    if (s.kind == FixedSelector::Kind::Label) {
      const std::string at = "fixed[" + std::to_string(k) + "].label";
      if (mesh.labels.empty()) throw Error(ErrorKind::Scenario, at + ": the mesh has no tet labels");
      bool any = false;
      for (size_t t = 0; t < mesh.tets.size(); ++t) {
        if (mesh.labels[t] != s.label) continue;
        any = true;
        for (int32_t p : mesh.tets[t]) fixed[p] = 1;
      }
      if (!any) throw Error(ErrorKind::Scenario, at + ": no tet has label " + std::to_string(s.label));
      continue;
    }
    bool any = false;
    for (int32_t i = 0; i < n; ++i) {
      if (!selector_matches(s, mesh.points[i])) continue;
      fixed[i] = 1;
      any = true;
    }
    // A selector written for another mesh, its units or its placement
    // would otherwise leave the model free, to fall under gravity.
    if (!any && n > 0) throw Error(ErrorKind::Scenario, no_point_selected(mesh, s, k));
  }
  if (n > 0 && std::all_of(fixed.begin(), fixed.end(), [](uint8_t f) { return f != 0; }))
    throw Error(ErrorKind::Scenario, "fixed: the selectors hold all " + std::to_string(n) +
                                         " points of the mesh, so nothing can move (a plane's normal points "
                                         "to the side it holds)");
  return fixed;
}

}  // namespace

double Model::total_mass() const { return std::accumulate(mass.begin(), mass.end(), 0.0); }

double Model::rest_volume() const { return std::accumulate(tet_rest_volume.begin(), tet_rest_volume.end(), 0.0); }

Model build_model(const TetMesh& mesh, const Material& material, const ModelOptions& options,
                  const std::string& source) {
  validate_tet_mesh(mesh, source);
  validate_material(material);
  std::vector<int32_t> mesh_tet_material;
  if (!options.label_materials.empty()) {
    for (size_t i = 0; i < options.label_materials.size(); ++i) {
      validate_material(options.label_materials[i].material, "materials[" + std::to_string(i) + "]");
    }
    check_materials_agree(options.label_materials);
    mesh_tet_material = tet_materials(mesh.labels, options.label_materials, source);
  }
  if (!options.gravity.allFinite()) throw Error(ErrorKind::Scenario, "gravity: expected finite numbers (m/s^2)");
  const int32_t npoint = static_cast<int32_t>(mesh.points.size());

  // Internal order: locality first (RCM), then valence within windows.
  const std::vector<Edge> input_edges = tet_edges(mesh.tets, npoint).ends;
  std::vector<int32_t> order(npoint);
  if (options.reorder_for_locality)
    order = reverse_cuthill_mckee(npoint, input_edges);
  else
    std::iota(order.begin(), order.end(), 0);
  std::vector<int32_t> valence(npoint, 0);
  for (const Edge& e : input_edges) {
    ++valence[e[0]];
    ++valence[e[1]];
  }
  sort_by_valence_in_windows(order, valence, options.sort_window);

  Model model;
  model.mesh_points = npoint;
  model.input_of_internal = order;
  model.internal_of_input.assign(npoint, -1);
  for (int32_t i = 0; i < npoint; ++i) model.internal_of_input[order[i]] = i;
  model.origin.resize(npoint);
  std::iota(model.origin.begin(), model.origin.end(), 0);
  const auto& to_internal = model.internal_of_input;

  model.rest_position.resize(npoint);
  for (int32_t i = 0; i < npoint; ++i) model.rest_position[i] = mesh.points[order[i]];

  // Tets (orientation unchanged by renumbering), sorted by their smallest
  // vertex so that neighbouring points share cache lines; labels and
  // materials follow their tets.
  std::vector<Tet> internal_tets(mesh.tets.size());
  for (size_t t = 0; t < mesh.tets.size(); ++t)
    for (int k = 0; k < 4; ++k) internal_tets[t][k] = to_internal[mesh.tets[t][k]];
  auto smallest = [](const Tet& t) { return *std::min_element(t.begin(), t.end()); };
  std::vector<int32_t> tet_order(mesh.tets.size());
  std::iota(tet_order.begin(), tet_order.end(), 0);
  std::stable_sort(tet_order.begin(), tet_order.end(),
                   [&](int32_t a, int32_t b) { return smallest(internal_tets[a]) < smallest(internal_tets[b]); });
  model.tet_points.resize(mesh.tets.size());
  for (size_t t = 0; t < tet_order.size(); ++t) {
    model.tet_points[t] = internal_tets[tet_order[t]];
    if (!mesh.labels.empty()) model.tet_label.push_back(mesh.labels[tet_order[t]]);
    if (!mesh_tet_material.empty()) model.tet_material.push_back(mesh_tet_material[tet_order[t]]);
  }
  model.tet_rest_volume.resize(model.tet_points.size());
  for (size_t t = 0; t < model.tet_points.size(); ++t) {
    const Tet& tet = model.tet_points[t];
    const auto& x = model.rest_position;
    model.tet_rest_volume[t] = signed_volume(x[tet[0]], x[tet[1]], x[tet[2]], x[tet[3]]);
  }

  const std::vector<uint8_t> fixed_input = select_fixed(mesh, options.fixed);
  std::vector<uint8_t> held(npoint);
  for (int32_t i = 0; i < npoint; ++i) held[i] = fixed_input[order[i]];

  model.gravity = options.gravity;
  model.material = options.label_materials.empty() ? material : options.label_materials.front().material;
  model.viscous_damping = model.material.viscous_damping;
  for (const LabelMaterial& m : options.label_materials) model.materials.push_back(m.material);
  assemble_model(model, held, options.chunk_size, options.sort_window);
  return model;
}

void assemble_model(Model& model, const std::vector<uint8_t>& held, int32_t chunk_size, int32_t sort_window) {
  const int32_t npoint = model.npoint();
  const Material& material = model.material;

  // Lumped masses: a quarter of each tet's mass to each of its vertices.
  model.mass.assign(npoint, 0.0);
  for (int32_t t = 0; t < model.ntet(); ++t)
    for (int32_t p : model.tet_points[t]) model.mass[p] += model.material_of_tet(t).density * model.tet_rest_volume[t] / 4.0;

  // Fixed points; points used by no tet have no mass and are held fixed.
  model.fixed.resize(npoint);
  model.inv_mass.resize(npoint);
  for (int32_t i = 0; i < npoint; ++i) {
    model.fixed[i] = held[i] || model.mass[i] <= 0;
    model.inv_mass[i] = model.fixed[i] ? 0.0 : 1.0 / model.mass[i];
  }

  model.tool_k_scale = tool_stiffness_scale(model.mass, model.fixed);

  // The boundary surface and each point's triangles on it, for the tool's
  // surface contact; a cut or tear changes it, so every version re-extracts it.
  model.surface = extract_boundary_faces(model.tet_points);
  model.surface_offset.assign(npoint + 1, 0);
  for (const Tri& t : model.surface)
    for (int32_t p : t) ++model.surface_offset[p + 1];
  for (int32_t p = 0; p < npoint; ++p) model.surface_offset[p + 1] += model.surface_offset[p];
  model.surface_tri.resize(model.surface_offset[npoint]);
  std::vector<int32_t> fill(model.surface_offset.begin(), model.surface_offset.end() - 1);
  for (int32_t t = 0; t < model.nsurface(); ++t)
    for (int32_t p : model.surface[t]) model.surface_tri[fill[p]++] = t;

  // Springs: one per unique tet edge, sorted.
  TetEdges edges = tet_edges(model.tet_points, npoint, model.tet_rest_volume);
  model.spring_ends = std::move(edges.ends);
  const int32_t nspring = model.nspring();
  model.spring_rest.resize(nspring);
  model.spring_d.resize(nspring);
  for (int32_t s = 0; s < nspring; ++s) {
    const auto [a, b] = model.spring_ends[s];
    model.spring_rest[s] = (model.rest_position[b] - model.rest_position[a]).norm();
  }
  // Stiffness from the material by the one rule in core/model/stiffness.h;
  // with per-label materials each tet adds its own share (the same sum over
  // tets that keeps stiffness when a cut splits them).
  if (model.tet_material.empty()) {
    model.spring_k = spring_stiffness(material, model.rest_position, model.spring_ends, edges.volume);
    for (int32_t s = 0; s < nspring; ++s) model.spring_d[s] = material.spring_damping_time * model.spring_k[s];
  } else {
    const PerTetSprings per_tet = per_tet_material_springs(model);
    model.spring_k = per_tet.k;
    model.spring_d = per_tet.d;
  }
  // Sutures after the tissue's springs: they have no tets, so the edge rule
  // above would drop them; a suture's damper follows the same damping time.
  for (const Suture& u : model.sutures) {
    model.spring_ends.push_back(u.ends);
    model.spring_rest.push_back(u.length);
    model.spring_k.push_back(u.k);
    model.spring_d.push_back(material.spring_damping_time * u.k);
  }
  // A cut splits a node patch: nodal volumes follow the new tets.
  model.point_rest_volume = nodal_rest_volume(npoint, model.tet_points, model.tet_rest_volume);
  if (model.tet_material.empty()) {
    model.tet_k = tet_volume_stiffness(material, model.tet_rest_volume);
    model.point_volume_k = nodal_volume_stiffness(material, model.point_rest_volume);
    // The shear element (nu < 1/4) follows the tets too; it never comes with a
    // volume term (stiffness.h), which lets the kernels treat them as one pass.
    model.tet_shear_k = tet_shear_stiffness(material, model.tet_rest_volume);
  } else {
    per_tet_material_volume_and_shear(model);
  }
  model.tet_shape_gradient.clear();
  model.shear_damping_time = model.has_shear_element() ? material.spring_damping_time : 0;
  model.shear_smoothed_share = shear_smoothed_share(material);
  model.point_shear_k.clear();
  if (model.has_smoothed_shear()) {
    model.point_shear_k.assign(npoint, 0.0);
    for (int32_t t = 0; t < model.ntet(); ++t)
      for (int32_t p : model.tet_points[t]) model.point_shear_k[p] += model.tet_shear_k[t];
  }
  if (model.has_shear_element()) {
    if (model.has_volume())
      throw Error(ErrorKind::Scenario, "material: the shear element (poisson_ratio < 0.25) and a volume term together");
    const auto& X = model.rest_position;
    for (const Tet& t : model.tet_points)
      model.tet_shape_gradient.push_back(shape_gradients(X[t[0]], X[t[1]], X[t[2]], X[t[3]]));
  }

  model.layout = build_gather_layout(model, chunk_size, sort_window);
}

bool selector_matches(const FixedSelector& s, const Vec3& x) {
  switch (s.kind) {
    case FixedSelector::Kind::Box:
      return (x.array() >= s.min.array()).all() && (x.array() <= s.max.array()).all();
    case FixedSelector::Kind::Plane:
      return (x - s.point).dot(s.normal) >= 0;
    case FixedSelector::Kind::Sphere:
      return (x - s.center).norm() <= s.radius;
    case FixedSelector::Kind::Indices:
    case FixedSelector::Kind::Label:
      return false;  // handled by id
  }
  return false;
}

}  // namespace organsim
