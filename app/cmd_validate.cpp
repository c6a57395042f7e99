// `organsim validate [-o OUTDIR] [--cell-size LIST] [--poisson-ratio LIST]`
// The force law against elasticity theory: uniaxial compression (E and nu),
// a cantilever with a tip load and with a guided end, and Hertz indentation,
// on CGAL meshes of boxes at several cell sizes. Writes validation.json,
// validation.csv and validation.png (error against cell size). SI units.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>

#include "app/command.h"
#include "app/validation_suite.h"
#include "core/model/stiffness.h"
#include "core/render/image_io.h"
#include "core/render/xy_plot.h"
#include "core/util/atomic_file.h"
#include "core/util/error.h"
#include "core/util/format.h"

namespace organsim::app {
namespace {

namespace fs = std::filesystem;

struct ValidateArgs {
  std::string outdir = "out/validation";
  std::vector<double> cell_sizes;
  std::vector<std::string> poisson_ratios;
  double young_modulus = 10e3;
  std::string volume_formulation;
  std::string shear_formulation;
  std::string contact = "surface";
  std::string hertz_layer;  // "on", "off"; empty: on with surface contact
  double line_load_reference = 0;  // m; 0: the line-load case is left out
  std::optional<double> contact_stiffness;  // N/m; the hertz-run case's penalty
  std::vector<std::string> cases;  // empty: every case
};

std::optional<double> parse_ratio(const std::string& text) {
  if (text == "springs") return std::nullopt;
  try {
    size_t used = 0;
    const double nu = std::stod(text, &used);
    if (used == text.size() && nu >= kMinPoissonRatio && nu < 0.5) return nu;
  } catch (const std::exception&) {
  }
  throw Error(ErrorKind::Usage, "--poisson-ratio: expected 'springs' or a number in [0, 0.5), got '" + text + "'");
}

void validate_command(const ValidateArgs& args) {
  SuiteOptions options;
  if (!args.cell_sizes.empty()) options.cell_sizes = args.cell_sizes;
  for (double h : options.cell_sizes)
    if (!(h > 0)) throw Error(ErrorKind::Usage, "--cell-size: expected positive sizes in m, got " + format_number(h));
  if (!args.poisson_ratios.empty()) {
    options.poisson_ratios.clear();
    for (const std::string& s : args.poisson_ratios) options.poisson_ratios.push_back(parse_ratio(s));
  }
  if (!(args.young_modulus > 0)) throw Error(ErrorKind::Usage, "--young-modulus: expected a positive number (Pa)");
  options.young_modulus = args.young_modulus;
  if (args.contact == "points")
    options.contact = ToolContact::Points;
  else if (args.contact != "surface")
    throw Error(ErrorKind::Usage, "--contact: expected 'surface' or 'points', got '" + args.contact + "'");
  if (args.hertz_layer == "on" && options.contact != ToolContact::Surface)
    throw Error(ErrorKind::Usage, "--hertz-layer on: the layer is the surface contact's (--contact surface)");
  if (!args.hertz_layer.empty() && args.hertz_layer != "on" && args.hertz_layer != "off")
    throw Error(ErrorKind::Usage, "--hertz-layer: expected 'on' or 'off', got '" + args.hertz_layer + "'");
  options.hertz_layer = options.contact == ToolContact::Surface && args.hertz_layer != "off";
  if (args.contact_stiffness) {
    if (!(*args.contact_stiffness > 0) || !std::isfinite(*args.contact_stiffness))
      throw Error(ErrorKind::Usage, "--contact-stiffness: expected a stiffness in N/m (> 0), got " +
                                        format_number(*args.contact_stiffness));
    options.run_contact_stiffness = *args.contact_stiffness;
  }
  if (args.line_load_reference < 0 || !std::isfinite(args.line_load_reference))
    throw Error(ErrorKind::Usage, "--line-load-reference: expected a cell size in m (> 0), got " +
                                      format_number(args.line_load_reference));
  if (args.line_load_reference > 0) options.line_load_reference = args.line_load_reference;
  for (const std::string& c : args.cases) {
    if (std::find(kSuiteCases.begin(), kSuiteCases.end(), c) == kSuiteCases.end()) {
      std::string names;
      for (const std::string& n : kSuiteCases) names += (names.empty() ? "" : ", ") + n;
      throw Error(ErrorKind::Usage, "--cases: expected some of " + names + ", got '" + c + "'");
    }
    if (c == "line-load" && !options.line_load_reference)
      throw Error(ErrorKind::Usage, "--cases line-load: the line load is compared with a reference mesh "
                                    "(--line-load-reference SIZE)");
  }
  options.cases = args.cases;
  if (args.volume_formulation == "nodal")
    options.volume_formulation = VolumeFormulation::Nodal;
  else if (args.volume_formulation == "per_tet")
    options.volume_formulation = VolumeFormulation::PerTet;
  else if (!args.volume_formulation.empty())
    throw Error(ErrorKind::Usage,
                "--volume-formulation: expected 'nodal' or 'per_tet', got '" + args.volume_formulation + "'");
  if (args.shear_formulation == "smoothed")
    options.shear_formulation = ShearFormulation::Smoothed;
  else if (args.shear_formulation == "per_tet")
    options.shear_formulation = ShearFormulation::PerTet;
  else if (!args.shear_formulation.empty())
    throw Error(ErrorKind::Usage,
                "--shear-formulation: expected 'smoothed' or 'per_tet', got '" + args.shear_formulation + "'");

  const bool tty = isatty(2);
  const auto rows = run_validation_suite(options, [tty](int done, int total, const std::string& what) {
    if (tty) std::cerr << "\r[" << done << "/" << total << "] " << what << "                    " << std::flush;
    if (tty && done == total) std::cerr << "\n";
  });

  const fs::path outdir(args.outdir);
  fs::create_directories(outdir);
  nlohmann::json j;
  j["units"] = "SI: cell_size m; measured and theory in Pa (E), N/m (beams), N (hertz, line load), 1 (nu)";
  j["young_modulus"] = options.young_modulus;
  j["indenter_radius"] = options.indenter_radius;
  j["probe_radius"] = options.probe_radius;
  j["contact"] = args.contact;
  j["hertz_layer"] = options.hertz_layer;
  j["run_contact_stiffness"] = options.run_contact_stiffness;
  j["cases"] = options.cases.empty() ? kSuiteCases : options.cases;
  if (options.line_load_reference)
    j["line_load"] = {{"block", {options.line_load_block.x(), options.line_load_block.y(), options.line_load_block.z()}},
                      {"depths", options.line_load_depths},
                      {"capsule_radius", options.line_load_radius},
                      {"reference_cell_size", *options.line_load_reference},
                      {"theory", "the same case's force on the reference mesh"}};
  j["method"] = "small-strain static equilibrium of the model's force law (core/validation/static_solve.h)";
  j["rows"] = nlohmann::json::array();
  for (const SuiteRow& r : rows) j["rows"].push_back(to_json(r));
  write_file_atomically(outdir / "validation.json", [&](std::ostream& out) { out << j.dump(2) << "\n"; });

  std::ostringstream csv;
  csv << "test,material,cell_size_m,points,measured,theory,error,error_kind,tolerance,pass\n";
  for (const SuiteRow& r : rows)
    csv << r.test << "," << r.material << "," << format_number(r.cell_size) << "," << r.points << ","
        << format_number(r.measured, "%.6g") << "," << format_number(r.theory, "%.6g") << ","
        << format_number(r.error, "%.4f") << "," << r.error_kind << ","
        << (r.tolerance ? format_number(*r.tolerance) : "") << "," << (r.tolerance ? (r.pass() ? "pass" : "fail") : "")
        << "\n";
  write_file_atomically(outdir / "validation.csv", [&](std::ostream& out) { out << csv.str(); });
  std::cout << csv.str();

  // One panel per test (measured / theory against cell size), one line per
  // material; Hertz at d/R = 0.1 only, small-strain and as run.
  std::vector<cv::Mat> panels;
  for (const char* test :
       {"uniaxial E", "cantilever tip load", "cantilever guided", "hertz d/R=0.1", "hertz as run d/R=0.1"}) {
    std::map<std::string, XySeries> by_material;
    std::vector<std::string> order;
    for (const SuiteRow& r : rows) {
      if (r.test != test) continue;
      if (!by_material.count(r.material)) order.push_back(r.material), by_material[r.material].name = r.material;
      by_material[r.material].x.push_back(r.cell_size * 1000);
      by_material[r.material].y.push_back(r.error);
    }
    std::vector<XySeries> series;
    for (const std::string& n : order) series.push_back(by_material[n]);
    XyPlotOptions plot;
    plot.width = 900;
    plot.height = 330;
    plot.title = std::string(test) + ": measured / theory (band +-10 %)";
    plot.x_label = "cell size (mm)";
    plot.y_label = "ratio";
    plot.band = std::make_pair(0.9, 1.1);
    panels.push_back(draw_xy_plot(series, plot));
  }
  cv::Mat sheet;
  cv::vconcat(panels, sheet);
  write_image_atomically(outdir / "validation.png", sheet);
  std::cout << "validation: " << (outdir / "validation.json").string() << ", validation.csv, validation.png\n";
}

const bool validate_registered = register_command("validate", 45, [](CLI::App& root) {
  auto args = std::make_shared<ValidateArgs>();
  CLI::App* cmd = root.add_subcommand(
      "validate", "The force law against elasticity theory (uniaxial E and nu, cantilever, Hertz) at several "
                  "mesh cell sizes [m]; writes validation.json, validation.csv and validation.png");
  cmd->add_option("-o,--output", args->outdir, "Output folder (default out/validation)");
  cmd->add_option("--cell-size", args->cell_sizes, "CGAL cell sizes, m (comma-separated; default 0.012,0.008,0.005)")
      ->delimiter(',');
  cmd->add_option("--poisson-ratio", args->poisson_ratios,
                  "Materials: 'springs' (no Poisson ratio, springs' nu = 1/4) or a Poisson ratio in [0, 0.5) "
                  "(comma-separated; default springs,0.3,0.45)")
      ->delimiter(',');
  cmd->add_option("--young-modulus", args->young_modulus, "Young's modulus, Pa (default 10000)");
  cmd->add_option("--volume-formulation", args->volume_formulation,
                  "Volume term of the Poisson-ratio materials: 'nodal' or 'per_tet' (default: the material's "
                  "default, docs/scenarios.md)");
  cmd->add_option("--shear-formulation", args->shear_formulation,
                  "Shear element of the materials below nu = 1/4, as a scenario's material.shear_formulation: "
                  "'smoothed' (default) or 'per_tet'");
  cmd->add_option("--contact", args->contact,
                  "The indenters' contact, as a scenario's tool.contact: 'surface' (the boundary triangles, "
                  "default) or 'points'");
  cmd->add_option("--hertz-layer", args->hertz_layer,
                  "The spheres' and the capsule's surface contact in series with the sub-cell layer, as a scenario's "
                  "tool.hertz_layer: 'on' (default with surface contact) or 'off'");
  cmd->add_option("--contact-stiffness", args->contact_stiffness,
                  "The hertz-run case's penalty, as a scenario's tool.contact_stiffness: N/m for a point of the "
                  "median mass (default 200, the scenario's default)");
  cmd->add_option("--cases", args->cases,
                  "Only these cases, comma-separated: uniaxial, cantilever, hertz (small strain), hertz-run (the "
                  "equilibrium a run settles into), probe, line-load (default: all; line-load needs "
                  "--line-load-reference)")
      ->delimiter(',');
  cmd->add_option("--line-load-reference", args->line_load_reference,
                  "Adds the line-load case (a capsule R 5 mm across a block, pressed 1, 2, 4 mm) compared with "
                  "itself on a mesh of this cell size, m (0.0025: converged; minutes per material)");
  cmd->callback([args] { validate_command(*args); });
});

}  // namespace
}  // namespace organsim::app
