// `organsim mesh INPUT -o OUTPUT`: tetrahedralise a closed surface or a
// labelled image (segmentation) with CGAL Mesh_3 (or read a tet mesh), report
// counts, quality, the springs-per-point histogram and each label's volume,
// and write .mesh, .vtk or .vtu. Input in other units is scaled to metres
// first (--scale, --units; an image's header unit); every size reported or
// written is in metres.
#include <chrono>
#include <map>
#include <optional>
#include <cmath>
#include <iostream>
#include <nlohmann/json.hpp>

#include "app/command.h"
#include "app/progress_line.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_stats.h"
#include "core/mesh/units.h"
#include "core/util/error.h"
#include "core/util/format.h"
#include "meshing/label_image.h"
#include "meshing/mesh_image.h"
#include "meshing/mesh_surface.h"

namespace organsim::app {
namespace {

struct MeshArgs {
  std::string input;
  std::string output;
  MeshOptions options;
  std::vector<std::string> cell_sizes;  // "H" for every label, "LABEL:H" for one label
  std::vector<int32_t> labels;          // --labels: keep only these labels of an image
  std::optional<double> scale;          // coordinates are multiplied by this (0.001 for a file in millimetres)
  std::string units;                    // or the unit named: mm, cm, m
  bool json = false;
};

// Metres per input unit, from --scale or --units (exclusive on the command
// line); nullopt when neither is given.
std::optional<double> given_scale(const MeshArgs& args) {
  if (!args.units.empty()) return *metres_per_unit(args.units);
  if (args.scale && (!(*args.scale > 0) || !std::isfinite(*args.scale))) {
    throw Error(ErrorKind::Usage, "--scale must be a positive number (metres per input unit), got " + format_number(*args.scale));
  }
  return args.scale;
}

double parse_size(const std::string& text, const std::string& option) {
  try {
    size_t used = 0;
    const double value = std::stod(text, &used);
    if (used == text.size()) return value;
  } catch (const std::exception&) {
  }
  throw Error(ErrorKind::Usage, option + ": '" + text + "' is not a number");
}

// --cell-size H (every label, or a surface) and --cell-size LABEL:H (one label of an image).
void parse_cell_sizes(const std::vector<std::string>& given, bool image, std::optional<double>& all,
                      std::map<int32_t, double>& per_label) {
  for (const std::string& text : given) {
    const size_t colon = text.find(':');
    if (colon == std::string::npos) {
      if (all) throw Error(ErrorKind::Usage, "--cell-size given twice without a label");
      all = parse_size(text, "--cell-size");
      continue;
    }
    if (!image) throw Error(ErrorKind::Usage, "--cell-size " + text + ": a size per label is for labelled images only");
    const double label = parse_size(text.substr(0, colon), "--cell-size label");
    if (label != std::floor(label) || label < 1 || label > 2147483647.0) {
      throw Error(ErrorKind::Usage, "--cell-size " + text + ": expected LABEL:SIZE with an integer label > 0");
    }
    per_label[static_cast<int32_t>(label)] = parse_size(text.substr(colon + 1), "--cell-size " + text);
  }
}

void run_mesh(const MeshArgs& args) {
  if (!is_tet_mesh_output_path(args.output)) {
    throw Error(ErrorKind::Usage, args.output + ": output must end in .mesh (medit), .vtk (VTK legacy) or .vtu (VTK XML)");
  }
  const std::optional<double> given = given_scale(args);
  const double scale = given.value_or(1.0);
  const bool image = is_label_image_path(args.input);
  if (!args.labels.empty() && !image) throw Error(ErrorKind::Usage, "--labels is for labelled images only");
  TetMesh mesh;
  MeshReport report;
  ProgressLine line;  // the meshing stage on stderr, only when it is a terminal
  if (image) {
    ImageMeshOptions options;
    options.target_points = args.options.target_points;
    parse_cell_sizes(args.cell_sizes, true, options.cell_size, options.label_cell_size);
    options.facet_distance = args.options.facet_distance;
    options.exude = args.options.exude;
    options.labels = args.labels;
    options.metres_per_unit = given;  // only for a header that names no unit
    options.on_stage = [&line](const std::string& stage) { line.show("organsim mesh: " + stage); };
    mesh = mesh_image_file(args.input, options, &report);
  } else if (is_tet_mesh_path(args.input)) {
    const auto start = std::chrono::steady_clock::now();
    mesh = read_tet_mesh(args.input);
    scale_points(mesh.points, scale);
    report = describe_tet_mesh(mesh);
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    report.notes.push_back(args.input + " is a tet mesh: read and converted, not remeshed");
  } else if (is_surface_path(args.input)) {
    // Scaled first, so that --cell-size and --facet-distance are metres of the scaled surface.
    TriangleMesh surface = read_surface(args.input);
    scale_points(surface.points, scale);
    MeshOptions options = args.options;
    std::map<int32_t, double> unused;
    parse_cell_sizes(args.cell_sizes, false, options.cell_size, unused);
    options.on_stage = [&line](const std::string& stage) { line.show("organsim mesh: " + stage); };
    mesh = mesh_surface(surface, options, args.input, &report);
  } else {
    throw input_error(args.input, "unknown extension '" + std::filesystem::path(args.input).extension().string() +
                                      "', expected a surface (.off .obj .stl .ply .vtp, .vtk polydata), a labelled "
                                      "image (.nii .nii.gz .nrrd .nhdr .inr .inr.gz) or a tet mesh (.mesh .msh .vtu, "
                                      ".vtk unstructured grid)");
  }
  if (scale != 1.0 && !image) {
    report.notes.insert(report.notes.begin(), "input scaled by " + format_number(scale) +
                                                  (args.units.empty() ? " (--scale)" : " (--units " + args.units + ")") +
                                                  " before meshing");
  }
  report.notes.push_back("sizes in metres: the mesh spans " + describe_extent(mesh.points) + ", volume " +
                         format_number(tet_mesh_volume(mesh)) + " m^3");
  line.show("organsim mesh: writing " + args.output);
  write_tet_mesh(args.output, mesh);
  line.clear();
  if (args.json) {
    nlohmann::json j = mesh_report_json(report);
    j["input"] = args.input;
    j["output"] = args.output;
    std::cout << j.dump(2) << "\n";
  } else {
    std::cout << "wrote " << args.output << "\n" << format_mesh_report(report);
  }
}

const bool mesh_registered = register_command("mesh", 10, [](CLI::App& root) {
  auto args = std::make_shared<MeshArgs>();
  CLI::App* cmd = root.add_subcommand(
      "mesh",
      "Tetrahedralise a closed triangle surface or a labelled image (CGAL Mesh_3), or convert a tet mesh; sizes in metres");
  cmd->add_option("input", args->input,
                  "closed surface (.off .obj .stl .ply .vtp, .vtk polydata), labelled image (.nii .nii.gz .nrrd "
                  ".nhdr .seg.nrrd .inr .inr.gz) or tet mesh (.mesh .msh .vtu, .vtk unstructured grid)")
      ->required();
  cmd->add_option("-o,--output", args->output, "tet mesh to write, in metres: .mesh (medit), .vtk (VTK legacy) or .vtu (VTK XML)")
      ->required();
  cmd->add_option("--target-points", args->options.target_points,
                                 "aim for this many points (within 10 %); searches the cell size");
  cmd->add_option("--cell-size", args->cell_sizes,
                               "max tet circumradius and facet size h, m (default: bounding-box diagonal / 20); "
                               "for an image also LABEL:H, repeatable, for one label (e.g. --cell-size 0.004 "
                               "--cell-size 2:0.0015); with --target-points only LABEL:H, and the target sizes "
                               "the other labels")
                   ->allow_extra_args(false);
  cmd->add_option("--facet-distance", args->options.facet_distance,
                  "max distance between the surface and the mesh boundary, m (default 0.1 h)");
  cmd->add_flag("--exude,!--no-exude", args->options.exude,
                "sliver exudation: min dihedral angle ~0.3 -> ~10 deg, 1.3-3x the meshing time (default on)");
  auto* scale = cmd->add_option("--scale", args->scale,
                                "multiply the input's coordinates by this first, e.g. 0.001 for a file in millimetres "
                                "(organsim works in metres); for an image only when its header names no unit");
  cmd->add_option("--labels", args->labels,
                  "mesh only these labels of an image, e.g. 1,2 (default: every label > 0; 0 is outside)")
      ->delimiter(',');
  cmd->add_option("--units", args->units, "the input's length unit, shorthand for --scale: mm (0.001), cm (0.01) or m")
      ->check(CLI::IsMember({"mm", "cm", "m"}))
      ->excludes(scale);
  cmd->add_flag("--json", args->json, "print the report as JSON");
  cmd->callback([args] { run_mesh(*args); });
});

}  // namespace
}  // namespace organsim::app
