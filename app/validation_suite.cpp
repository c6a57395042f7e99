#include "app/validation_suite.h"

#include <algorithm>

#include <cstdio>

#include "core/mesh/example_shapes.h"
#include "core/validation/elastic_cases.h"
#include "meshing/mesh_surface.h"

namespace organsim::app {

namespace {

std::string material_name(const std::optional<double>& nu) {
  if (!nu) return "springs (nu 1/4)";
  char buf[32];
  std::snprintf(buf, sizeof buf, "nu %.2f", *nu);
  return buf;
}

TetMesh mesh_box(const Vec3& size, double cell_size) {
  MeshOptions options;
  options.cell_size = cell_size;
  return mesh_surface(make_box_surface(Vec3::Zero(), size), options, "validation box");
}

Material suite_material(const SuiteOptions& options, const std::optional<double>& nu) {
  Material m;
  m.young_modulus = options.young_modulus;
  m.poisson_ratio = nu;
  if (nu) m.volume_formulation = options.volume_formulation;
  if (options.shear_formulation) m.shear_formulation = *options.shear_formulation;
  return m;
}

// The line-load case's target: within 15 % of the reference mesh's force.
constexpr double kLineLoadTolerance = 0.15;

}  // namespace

bool SuiteOptions::runs(const std::string& name) const {
  if (name == "line-load" && !line_load_reference) return false;
  return cases.empty() || std::find(cases.begin(), cases.end(), name) != cases.end();
}

std::vector<SuiteRow> run_validation_suite(const SuiteOptions& options,
                                           const std::function<void(int, int, const std::string&)>& progress) {
  // Shapes: a block for uniaxial compression, a 10:1 beam, and the issue's
  // indentation box (a half-space for a contact radius of a few mm).
  const Vec3 block(0.06, 0.06, 0.09), beam(0.2, 0.02, 0.02), slab(0.10, 0.08, 0.06);
  const std::vector<double> depth_ratios{0.05, 0.1, 0.2};
  const int total = static_cast<int>(options.cell_sizes.size() * options.poisson_ratios.size());
  int done = 0;
  std::vector<SuiteRow> rows;
  // The line-load case's reference: the same case on the refined mesh, per material.
  std::vector<LineLoadResult> line_load_reference;
  if (options.runs("line-load")) {
    const TetMesh reference = mesh_box(options.line_load_block, *options.line_load_reference);
    for (const auto& nu : options.poisson_ratios) {
      if (progress) progress(done, total, material_name(nu) + ", line-load reference");
      line_load_reference.push_back(capsule_line_load(reference, suite_material(options, nu), options.line_load_radius,
                                                      options.line_load_depths, options.hertz_layer));
    }
  }
  for (double h : options.cell_sizes) {
    // Only the meshes of the cases asked for.
    const auto mesh_if = [&](bool wanted, const Vec3& size) { return wanted ? mesh_box(size, h) : TetMesh{}; };
    const TetMesh block_mesh = mesh_if(options.runs("uniaxial"), block);
    const TetMesh beam_mesh = mesh_if(options.runs("cantilever"), beam);
    const TetMesh slab_mesh = mesh_if(options.runs("hertz") || options.runs("hertz-run") || options.runs("probe"), slab);
    const TetMesh line_mesh = mesh_if(options.runs("line-load"), options.line_load_block);
    for (size_t material = 0; material < options.poisson_ratios.size(); ++material) {
      const auto& nu = options.poisson_ratios[material];
      const Material m = suite_material(options, nu);
      const std::string name = material_name(nu);
      if (progress) progress(done, total, name + ", cell size " + std::to_string(h) + " m");
      const double asked_nu = nu.value_or(0.25);
      auto add = [&](const std::string& test, int32_t points, double measured, double theory, bool ratio,
                     std::optional<double> tolerance = std::nullopt) {
        rows.push_back({test, name, h, points, measured, theory, ratio ? measured / theory : measured - theory,
                        ratio ? "ratio" : "difference", tolerance});
      };
      if (options.runs("uniaxial")) {
        const UniaxialResult u = uniaxial_compression(block_mesh, m);
        add("uniaxial E", u.points, u.young_modulus, m.young_modulus, true);
        add("uniaxial nu", u.points, u.poisson_ratio, asked_nu, false);
      }
      if (options.runs("cantilever")) {
        const BeamResult tip = cantilever(beam_mesh, m, BeamEnd::TipLoad);
        add("cantilever tip load", tip.points, tip.stiffness, tip.timoshenko, true);
        const BeamResult guided = cantilever(beam_mesh, m, BeamEnd::Guided);
        add("cantilever guided", guided.points, guided.stiffness, guided.timoshenko, true);
      }
      if (options.runs("hertz")) {
        std::vector<double> depths;
        for (double r : depth_ratios) depths.push_back(r * options.indenter_radius);
        const IndentationResult hz = sphere_indentation(slab_mesh, m, options.indenter_radius, depths,
                                                          options.contact, options.hertz_layer);
        for (size_t i = 0; i < depths.size(); ++i) {
          char test[48];
          std::snprintf(test, sizeof test, "hertz d/R=%.2g", depth_ratios[i]);
          add(test, hz.points, hz.force[i], hz.hertz[i], true);
        }
      }
      if (options.runs("hertz-run")) {
        std::vector<double> depths;
        for (double r : depth_ratios) depths.push_back(r * options.indenter_radius);
        const IndentationResult hz = sphere_indentation(slab_mesh, m, options.indenter_radius, depths, options.contact,
                                                          options.hertz_layer, AsRun{options.run_contact_stiffness});
        for (size_t i = 0; i < depths.size(); ++i) {
          char test[48];
          std::snprintf(test, sizeof test, "hertz as run d/R=%.2g", depth_ratios[i]);
          add(test, hz.points, hz.force[i], hz.hertz[i], true);
        }
      }
      if (options.runs("probe")) {
        // A probe smaller than a cell (an instrument's tip), at d/R = 0.2.
        const IndentationResult probe =
            sphere_indentation(slab_mesh, m, options.probe_radius, {0.2 * options.probe_radius}, options.contact,
                               options.hertz_layer);
        add("hertz probe d/R=0.2", probe.points, probe.force[0], probe.hertz[0], true);
      }
      if (options.runs("line-load")) {
        const LineLoadResult line = capsule_line_load(line_mesh, m, options.line_load_radius, options.line_load_depths,
                                                     options.hertz_layer);
        const LineLoadResult& reference = line_load_reference[material];
        for (size_t i = 0; i < options.line_load_depths.size(); ++i) {
          char test[48];
          std::snprintf(test, sizeof test, "line load d=%gmm", options.line_load_depths[i] * 1000);
          add(test, line.points, -line.force[i].z(), -reference.force[i].z(), true, kLineLoadTolerance);
        }
      }
      ++done;
    }
  }
  if (progress) progress(done, total, "done");
  return rows;
}

nlohmann::json to_json(const SuiteRow& r) {
  nlohmann::json j{{"test", r.test},         {"material", r.material}, {"cell_size", r.cell_size},
                   {"points", r.points},     {"measured", r.measured}, {"theory", r.theory},
                   {"error", r.error},       {"error_kind", r.error_kind}};
  if (r.tolerance) j["tolerance"] = *r.tolerance, j["pass"] = r.pass();
  return j;
}

}  // namespace organsim::app
