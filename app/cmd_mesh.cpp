// `organsim mesh INPUT -o OUTPUT`: tetrahedralise a closed surface with CGAL
// Mesh_3 (or read a tet mesh), report counts, quality and the springs-per-point
// histogram, and write .mesh or .vtk. Sizes in metres.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <iostream>
#include <nlohmann/json.hpp>

#include "app/command.h"
#include "app/progress_line.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_stats.h"
#include "core/util/error.h"
#include "meshing/mesh_surface.h"

namespace organsim::app {
namespace {

struct MeshArgs {
  std::string input;
  std::string output;
  MeshOptions options;
  double scale = 1.0;  // coordinates are multiplied by this (0.001 for a file in millimetres)
  bool json = false;
};

void run_mesh(const MeshArgs& args) {
  std::string ext = std::filesystem::path(args.output).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext != ".mesh" && ext != ".vtk") {
    throw Error(ErrorKind::Usage, args.output + ": output must end in .mesh (medit) or .vtk (VTK legacy)");
  }
  if (!(args.scale > 0) || !std::isfinite(args.scale)) {
    throw Error(ErrorKind::Usage, "--scale must be a positive number, got " + std::to_string(args.scale));
  }
  TetMesh mesh;
  MeshReport report;
  ProgressLine line;  // the meshing stage on stderr, only when it is a terminal
  if (is_tet_mesh_path(args.input)) {
    const auto start = std::chrono::steady_clock::now();
    mesh = read_tet_mesh(args.input);
    for (Vec3& p : mesh.points) p *= args.scale;
    report = describe_tet_mesh(mesh);
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    report.notes.push_back(args.input + " is a tet mesh: read and converted, not remeshed");
  } else if (is_surface_path(args.input)) {
    TriangleMesh surface = read_surface(args.input);
    for (Vec3& p : surface.points) p *= args.scale;
    MeshOptions options = args.options;
    options.on_stage = [&line](const std::string& stage) { line.show("organsim mesh: " + stage); };
    mesh = mesh_surface(surface, options, args.input, &report);
  } else {
    throw input_error(args.input, "unknown extension '" + std::filesystem::path(args.input).extension().string() +
                                      "', expected a surface (.off .obj .stl .ply) or a tet mesh (.mesh .vtk .msh)");
  }
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
  cmd->add_option("input", args->input, "closed surface (.off .obj .stl .ply) or tet mesh (.mesh .vtk .msh)")
      ->required();
  cmd->add_option("-o,--output", args->output, "tet mesh to write: .mesh (medit) or .vtk (VTK legacy)")->required();
  auto* target = cmd->add_option("--target-points", args->options.target_points,
                                 "aim for this many points (within 10 %); searches the cell size");
  auto* cell = cmd->add_option("--cell-size", args->options.cell_size,
                               "max tet circumradius and facet size h, m (default: bounding-box diagonal / 20)");
  target->excludes(cell);
  cmd->add_option("--facet-distance", args->options.facet_distance,
                  "max distance between the surface and the mesh boundary, m (default 0.1 h)");
  cmd->add_flag("--exude,!--no-exude", args->options.exude,
                "sliver exudation: min dihedral angle ~0.3 -> ~10 deg, 1.3-3x the meshing time (default on)");
  cmd->add_option("--scale", args->scale,
                  "multiply the input's coordinates by this first, e.g. 0.001 for a file in millimetres "
                  "(organsim works in metres)");
  cmd->add_flag("--json", args->json, "print the report as JSON");
  cmd->callback([args] { run_mesh(*args); });
});

}  // namespace
}  // namespace organsim::app
