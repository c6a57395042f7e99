// `organsim mesh INPUT -o OUTPUT`: tetrahedralise a closed surface with CGAL
// Mesh_3 (or read a tet mesh), report counts, quality and the springs-per-point
// histogram, and write .mesh, .vtk or .vtu. Input in other units is scaled to
// metres first (--scale, --units); every size reported or written is in metres.
#include <chrono>
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
#include "meshing/mesh_surface.h"

namespace organsim::app {
namespace {

struct MeshArgs {
  std::string input;
  std::string output;
  MeshOptions options;
  double scale = 1.0;  // coordinates are multiplied by this (0.001 for a file in millimetres)
  std::string units;   // or the unit named: mm, cm, m
  bool json = false;
};

// Metres per input unit, from --scale or --units (exclusive on the command line).
double input_scale(const MeshArgs& args) {
  if (!args.units.empty()) return *metres_per_unit(args.units);
  if (!(args.scale > 0) || !std::isfinite(args.scale)) {
    throw Error(ErrorKind::Usage, "--scale must be a positive number (metres per input unit), got " + format_number(args.scale));
  }
  return args.scale;
}

void run_mesh(const MeshArgs& args) {
  if (!is_tet_mesh_output_path(args.output)) {
    throw Error(ErrorKind::Usage, args.output + ": output must end in .mesh (medit), .vtk (VTK legacy) or .vtu (VTK XML)");
  }
  const double scale = input_scale(args);
  TetMesh mesh;
  MeshReport report;
  ProgressLine line;  // the meshing stage on stderr, only when it is a terminal
  if (is_tet_mesh_path(args.input)) {
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
    options.on_stage = [&line](const std::string& stage) { line.show("organsim mesh: " + stage); };
    mesh = mesh_surface(surface, options, args.input, &report);
  } else {
    throw input_error(args.input, "unknown extension '" + std::filesystem::path(args.input).extension().string() +
                                      "', expected a surface (.off .obj .stl .ply .vtp, .vtk polydata) or a tet "
                                      "mesh (.mesh .msh .vtu, .vtk unstructured grid)");
  }
  if (scale != 1.0) {
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

const bool registered = register_command("mesh", 10, [](CLI::App& root) {
  auto args = std::make_shared<MeshArgs>();
  CLI::App* cmd = root.add_subcommand(
      "mesh", "Tetrahedralise a closed triangle surface (CGAL Mesh_3) or convert a tet mesh; sizes in metres");
  cmd->add_option("input", args->input,
                  "closed surface (.off .obj .stl .ply .vtp, .vtk polydata) or tet mesh (.mesh .msh .vtu, .vtk "
                  "unstructured grid)")
      ->required();
  cmd->add_option("-o,--output", args->output, "tet mesh to write, in metres: .mesh (medit), .vtk (VTK legacy) or .vtu (VTK XML)")
      ->required();
  auto* target = cmd->add_option("--target-points", args->options.target_points,
                                 "aim for this many points (within 10 %); searches the cell size");
  auto* cell = cmd->add_option("--cell-size", args->options.cell_size,
                               "max tet circumradius and facet size h, m (default: bounding-box diagonal / 20)");
  target->excludes(cell);
  cmd->add_option("--facet-distance", args->options.facet_distance,
                  "max distance between the surface and the mesh boundary, m (default 0.1 h)");
  cmd->add_flag("--exude,!--no-exude", args->options.exude,
                "sliver exudation: min dihedral angle ~0.3 -> ~10 deg, 1.3-3x the meshing time (default on)");
  auto* scale = cmd->add_option("--scale", args->scale,
                                "multiply the input's coordinates by this first, e.g. 0.001 for a file in millimetres "
                                "(organsim works in metres)");
  cmd->add_option("--units", args->units, "the input's length unit, shorthand for --scale: mm (0.001), cm (0.01) or m")
      ->check(CLI::IsMember({"mm", "cm", "m"}))
      ->excludes(scale);
  cmd->add_flag("--json", args->json, "print the report as JSON");
  cmd->callback([args] { run_mesh(*args); });
});

}  // namespace
}  // namespace organsim::app
