// `organsim example liver|sphere|box -o FILE [--units mm]`: writes the example
// surfaces that examples/ holds, so they can be regenerated (sizes in metres,
// or in the unit asked for, as a CT segmentation in millimetres would be).
#include <iostream>

#include "app/command.h"
#include "core/mesh/example_shapes.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_stats.h"
#include "core/mesh/units.h"
#include "core/util/error.h"

namespace organsim::app {
namespace {

struct ExampleArgs {
  std::string shape;
  std::string output;
  int subdivisions = 4;
  double radius = 0.05;
  std::string units = "m";
};

void run_example(const ExampleArgs& args) {
  if (args.subdivisions < 0 || args.subdivisions > 7) {
    throw Error(ErrorKind::Usage, "--subdivisions must be in [0, 7], got " + std::to_string(args.subdivisions));
  }
  if (!is_surface_output_path(args.output)) {
    throw Error(ErrorKind::Usage,
                args.output + ": expected a surface file name ending in .off, .obj, .stl, .ply, .vtk or .vtp");
  }
  TriangleMesh surface = make_example_surface(args.shape, args.subdivisions, args.radius);  // metres
  const double volume = surface_volume(surface);
  const double metres = *metres_per_unit(args.units);
  scale_points(surface.points, 1.0 / metres);
  round_points(surface, 1e-6 / metres);  // micrometres: short files that read back exactly
  write_surface(args.output, surface);
  std::cout << "wrote " << args.output << ": " << args.shape << ", " << surface.points.size() << " points, "
            << surface.faces.size() << " triangles, volume " << volume << " m^3, coordinates in " << args.units
            << "\n";
}

const bool example_registered = register_command("example", 90, [](CLI::App& root) {
  auto args = std::make_shared<ExampleArgs>();
  CLI::App* cmd = root.add_subcommand("example", "Write an example closed surface (liver-like, sphere or box; metres)");
  cmd->add_option("shape", args->shape, "liver (about 0.21 x 0.15 x 0.10 m), sphere or box (0.10 x 0.08 x 0.06 m)")
      ->required()
      ->check(CLI::IsMember({"liver", "sphere", "box"}));
  cmd->add_option("-o,--output", args->output, "surface file to write (.off .obj .stl .ply .vtk .vtp)")->required();
  cmd->add_option("--units", args->units, "length unit of the written coordinates: m (default), cm or mm")
      ->check(CLI::IsMember({"mm", "cm", "m"}));
  cmd->add_option("--subdivisions", args->subdivisions,
                  "icosphere subdivisions for liver and sphere: 20 * 4^s triangles (default 4: 5120)");
  cmd->add_option("--radius", args->radius, "sphere radius, m (default 0.05)");
  cmd->callback([args] { run_example(*args); });
});

}  // namespace
}  // namespace organsim::app
