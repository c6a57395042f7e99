#pragma once
// The validation suite behind `organsim validate`: each elastic case of
// core/validation/elastic_cases.h on CGAL meshes of its box at several cell
// sizes and for several materials, compared with theory. In app/ because it
// meshes with CGAL (meshing/).
#include <nlohmann/json.hpp>
#include <cmath>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/model/material.h"
#include "core/scenario/tool_spec.h"
#include "core/sim/tool.h"
#include "core/util/vec.h"

namespace organsim::app {

struct SuiteOptions {
  std::vector<double> cell_sizes{0.012, 0.008, 0.005};  // m (CGAL max circumradius)
  // One material per entry, E = young_modulus: an empty optional is the
  // springs-only rule (no Poisson ratio, nu = 1/4), else that Poisson ratio.
  std::vector<std::optional<double>> poisson_ratios{std::nullopt, 0.3, 0.45};
  // Form of the volume term for the Poisson-ratio materials; unset = the
  // material's default (volume_formulation() in core/model/stiffness.h).
  std::optional<VolumeFormulation> volume_formulation;
  // Form of the shear element of the materials below nu = 1/4; unset = the
  // material's default (smoothed).
  std::optional<ShearFormulation> shear_formulation;
  double young_modulus = 10e3;   // Pa
  double indenter_radius = 0.02; // m
  double probe_radius = 0.005;   // m: the small probe, pressed to d/R = 0.2
  ToolContact contact = ToolContact::Surface;  // the indenters' contact, as a scenario's tool.contact
  bool hertz_layer = true;  // surface contact in series with the sub-cell layer (tool.hertz_layer): a sphere's Hertz layer, the capsule's line layer
  // The hertz-run case's penalty, as a scenario's tool.contact_stiffness
  // (N/m for a point of the median mass; default the scenario's).
  double run_contact_stiffness = ToolSpec{}.contact_stiffness;
  // The line-load case (a capsule across a block, capsule_line_load) is
  // compared with itself on a mesh of this cell size (m); unset leaves the
  // case out, since a converged reference (2.5 mm) takes minutes per material.
  std::optional<double> line_load_reference;
  double line_load_radius = 0.005;  // m: the capsule (a 10 mm instrument shaft)
  // The block (m; the capsule lies along y, across its 4 cm) and the depths (m).
  Vec3 line_load_block{0.08, 0.04, 0.03};
  std::vector<double> line_load_depths{0.001, 0.002, 0.004};
  // The cases to run, from kSuiteCases; empty: every one (the line load
  // only with its reference).
  std::vector<std::string> cases;
  bool runs(const std::string& name) const;
};

// The suite's case names, in the order they run.
inline const std::vector<std::string> kSuiteCases{"uniaxial", "cantilever", "hertz", "hertz-run", "probe", "line-load"};

// One measured quantity against its theory.
struct SuiteRow {
  std::string test;       // "uniaxial E", "uniaxial nu", "cantilever tip load", "cantilever guided", "hertz d/R=0.1",
                          // "hertz as run d/R=0.1" (the same, at the equilibrium a run settles into),
                          // "hertz probe d/R=0.2" (the small probe), "line load d=2mm" (against the reference mesh)
  std::string material;   // "springs (nu 1/4)" or "nu 0.30"
  double cell_size = 0;   // m
  int32_t points = 0;
  double measured = 0, theory = 0;
  // measured / theory for forces and moduli; measured - theory for nu.
  double error = 0;
  std::string error_kind;  // "ratio" or "difference"
  // The target where the case has one: pass when |error - 1| <= tolerance
  // (ratios only).
  std::optional<double> tolerance;
  bool pass() const { return tolerance && std::abs(error - 1) <= *tolerance; }
};

// Runs every case; `progress(done, total, what)` is called between cases.
std::vector<SuiteRow> run_validation_suite(const SuiteOptions& options,
                                           const std::function<void(int, int, const std::string&)>& progress);

nlohmann::json to_json(const SuiteRow& row);

}  // namespace organsim::app
