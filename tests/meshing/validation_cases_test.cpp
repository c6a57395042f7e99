// The force law against elasticity theory on CGAL meshes at the liver
// scenarios' resolution (8 mm cells: liver.off at 2500 points), the small
// version of `organsim validate` (docs/validation.md has the full tables).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

#include "core/mesh/example_shapes.h"
#include "core/sim/cpu_backend.h"
#include "core/validation/elastic_cases.h"
#include "core/validation/run_equilibrium.h"
#include "meshing/mesh_surface.h"

namespace organsim {
namespace validation_cases_test {
namespace {

constexpr double kLiverCellSize = 0.008;  // m

TetMesh box(const Vec3& size, double cell_size) {
  MeshOptions options;
  options.cell_size = cell_size;
  return mesh_surface(make_box_surface(Vec3::Zero(), size), options, "test box");
}

Material material(double nu) {
  Material m;
  m.young_modulus = 10e3;
  m.poisson_ratio = nu;
  return m;
}

TEST(ValidationCases, UniaxialCompressionGivesTheAskedPoissonRatioAndModulus) {
  const TetMesh block = box(Vec3(0.06, 0.06, 0.09), kLiverCellSize);
  for (double nu : {0.25, 0.35, 0.45}) {
    const UniaxialResult r = uniaxial_compression(block, material(nu));
    // The target: measured nu within 0.03 of the asked one (nodal
    // volume term from 0.35 up: measured within 0.012 at 8 mm).
    EXPECT_NEAR(r.poisson_ratio, nu, 0.03) << "asked nu " << nu;
    // E within 10 % from nu 0.3 up. The springs-only lattice (nu 0.25,
    // no volume term) is ~10 % soft here (0.90 measured): the irregular
    // network relaxes non-affinely (docs/validation.md), so 12 % for it.
    const double tolerance = nu < 0.3 ? 0.12 : 0.10;
    EXPECT_NEAR(r.young_modulus / 10e3, 1.0, tolerance) << "asked nu " << nu;
  }
}

TEST(ValidationCases, UniaxialCompressionBelowAQuarterWithTheShearElement) {
  // Below 1/4 the springs carry lambda and the shear element mu - lambda
  // (at nu 0 the element alone). Target: measured nu within 0.03.
  const TetMesh block = box(Vec3(0.06, 0.06, 0.09), kLiverCellSize);
  for (double nu : {0.0, 0.1, 0.2}) {
    const UniaxialResult r = uniaxial_compression(block, material(nu));
    EXPECT_NEAR(r.poisson_ratio, nu, 0.03) << "asked nu " << nu;
    EXPECT_NEAR(r.young_modulus / 10e3, 1.0, 0.10) << "asked nu " << nu;
  }
}

TEST(ValidationCases, CantileverMatchesBeamTheoryWithinTenPercent) {
  // 0.2 x 0.02 x 0.02 m: 2-3 cells through the thickness at 8 mm. At nu 0.45
  // the nodal volume term (the default with poisson_ratio) is within the
  // issue's 10 % (measured 1.02 tip, 0.99 guided); the per-tet term locks
  // there (1.43, 1.44), which the last check guards.
  const TetMesh beam = box(Vec3(0.2, 0.02, 0.02), kLiverCellSize);
  const BeamResult tip = cantilever(beam, material(0.45), BeamEnd::TipLoad);
  EXPECT_NEAR(tip.stiffness / tip.timoshenko, 1.0, 0.10);
  const BeamResult guided = cantilever(beam, material(0.45), BeamEnd::Guided);
  EXPECT_NEAR(guided.stiffness / guided.timoshenko, 1.0, 0.10);
  // The guided end is four times stiffer in bending (12 vs 3 E I / L^3).
  EXPECT_NEAR(guided.euler_bernoulli / tip.euler_bernoulli, 4.0, 1e-12);
  // nu 0.3: the tip load within 10 % (0.96); the guided end is 0.89, as soft
  // as the springs alone (0.89): the irregular lattice's non-affine
  // relaxation (docs/validation.md), so 12 % there.
  const BeamResult tip_03 = cantilever(beam, material(0.3), BeamEnd::TipLoad);
  EXPECT_NEAR(tip_03.stiffness / tip_03.timoshenko, 1.0, 0.10);
  const BeamResult guided_03 = cantilever(beam, material(0.3), BeamEnd::Guided);
  EXPECT_NEAR(guided_03.stiffness / guided_03.timoshenko, 1.0, 0.12);
  // Locking of the per-tet term at nu 0.45: more than 30 % too stiff.
  Material per_tet = material(0.45);
  per_tet.volume_formulation = VolumeFormulation::PerTet;
  const BeamResult locked = cantilever(beam, per_tet, BeamEnd::TipLoad);
  EXPECT_GT(locked.stiffness / locked.timoshenko, 1.3);
}

TEST(ValidationCases, CantileverBelowAQuarterWithinTenPercentWithTheSmoothedElement) {
  // Below 1/4 the shear element carries mu - lambda (all of it at nu 0). A
  // constant-strain tet cannot bend, so per tet it locks with 2-3 cells
  // through the beam (1.35 tip / 1.30 guided at nu 0); the smoothed form
  // (half on node-averaged gradients, the default) measured 1.03-1.05 tip
  // and 0.97-1.01 guided for nu 0, 0.1, 0.2: the 10 %.
  const TetMesh beam = box(Vec3(0.2, 0.02, 0.02), kLiverCellSize);
  for (double nu : {0.0, 0.1, 0.2}) {
    const BeamResult tip = cantilever(beam, material(nu), BeamEnd::TipLoad);
    EXPECT_NEAR(tip.stiffness / tip.timoshenko, 1.0, 0.10) << "asked nu " << nu;
    const BeamResult guided = cantilever(beam, material(nu), BeamEnd::Guided);
    EXPECT_NEAR(guided.stiffness / guided.timoshenko, 1.0, 0.10) << "asked nu " << nu;
  }
  // The per-tet form still locks: what the smoothing is for.
  Material per_tet = material(0.0);
  per_tet.shear_formulation = ShearFormulation::PerTet;
  const BeamResult locked = cantilever(beam, per_tet, BeamEnd::TipLoad);
  EXPECT_GT(locked.stiffness / locked.timoshenko, 1.25);
}

// Point contact (tool.contact "points").
TEST(ValidationCases, HertzContactConvergesOnceTheContactIsResolved) {
  // A 2 cm sphere 2 mm deep (d/R = 0.1, contact radius 6.3 mm). At 8 mm
  // cells the contact is under one cell and the force is outside Hertz's
  // 10 % either way, by how many points the sphere happens to catch (1.19
  // of Hertz on the portable build's mesh, 0.83 on the one a -march=native
  // build of CGAL made: the nodes move with the instruction set). At 4 mm
  // cells it is within 10 % (1.00; on the portable build's meshes 4.5 mm
  // gives 1.12, 5 mm 1.21, 3.5 mm 1.07). The coarse run is the reason
  // docs/validation.md gives the contact radius a cell size needs.
  const Vec3 slab(0.10, 0.08, 0.06);
  const IndentationResult coarse =
      sphere_indentation(box(slab, kLiverCellSize), material(0.3), 0.02, {0.002}, ToolContact::Points);
  const IndentationResult fine = sphere_indentation(box(slab, 0.004), material(0.3), 0.02, {0.002}, ToolContact::Points);
  EXPECT_NEAR(fine.force[0] / fine.hertz[0], 1.0, 0.10);
  EXPECT_GT(std::abs(coarse.force[0] / coarse.hertz[0] - 1.0), 0.10);
  EXPECT_GT(fine.contacts[0], coarse.contacts[0]);
}

// Surface contact (the default) at 8 mm cells: every boundary triangle must
// stay out of the sphere, a stronger condition than its corners alone, so
// the force is never below point contact's; at these cells the contact
// spans one to three triangles, which move as planes, so it is above
// Hertz (measured 2.36, 1.74, 1.41 at d/R 0.05, 0.1, 0.2, nu 0.45;
// docs/validation.md). The band 1 to 2.6 holds those figures with room
// for meshing differences; a contact that let the sphere sink between
// points would fall below 1 as point contact does (0.2-0.7).
TEST(ValidationCases, HertzWithSurfaceContactIsNeverBelowPointContact) {
  const Vec3 slab(0.10, 0.08, 0.06);
  const double radius = 0.02;
  const std::vector<double> depths{0.05 * radius, 0.1 * radius, 0.2 * radius};
  const TetMesh mesh = box(slab, kLiverCellSize);
  const IndentationResult surface = sphere_indentation(mesh, material(0.45), radius, depths);
  const IndentationResult points = sphere_indentation(mesh, material(0.45), radius, depths, ToolContact::Points);
  for (size_t i = 0; i < depths.size(); ++i) {
    std::cout << "hertz at 8 mm, d/R " << depths[i] / radius << ": surface contact " << surface.force[i] / surface.hertz[i]
              << ", point contact " << points.force[i] / points.hertz[i] << " of theory\n";
    EXPECT_GE(surface.force[i], points.force[i] * (1 - 1e-3)) << "d/R " << depths[i] / radius;
    EXPECT_GT(surface.force[i] / surface.hertz[i], 1.0) << "d/R " << depths[i] / radius;
    EXPECT_LT(surface.force[i] / surface.hertz[i], 2.6) << "d/R " << depths[i] / radius;
  }
}

// The sub-cell Hertz layer (tool.hertz_layer) in series with the surface
// contact at 8 mm cells, nu 0.45: the targets, Hertz within 15 % at
// d/R 0.05, 0.1 and 0.2 (R 2 cm; measured 0.93, 0.94, 1.01, its factor
// fitted to the middle one) and the 5 mm probe within 25 % at d/R 0.2
// (measured 0.96). Without the layer the same contact is 1.4-2.4 times
// Hertz and the probe 4.5 times.
TEST(ValidationCases, HertzWithTheSubCellLayerIsWithinFifteenPercentAtTheLiversCells) {
  const Vec3 slab(0.10, 0.08, 0.06);
  const double radius = 0.02, probe = 0.005;
  const std::vector<double> depths{0.05 * radius, 0.1 * radius, 0.2 * radius};
  const TetMesh mesh = box(slab, kLiverCellSize);
  const IndentationResult hertz = sphere_indentation(mesh, material(0.45), radius, depths, ToolContact::Surface, true);
  for (size_t i = 0; i < depths.size(); ++i) {
    std::cout << "hertz at 8 mm with the layer, d/R " << depths[i] / radius << ": " << hertz.force[i] / hertz.hertz[i]
              << " of theory\n";
    EXPECT_NEAR(hertz.force[i] / hertz.hertz[i], 1.0, 0.15) << "d/R " << depths[i] / radius;
  }
  const IndentationResult tip = sphere_indentation(mesh, material(0.45), probe, {0.2 * probe}, ToolContact::Surface, true);
  std::cout << "probe R 5 mm at 8 mm with the layer, d/R 0.2: " << tip.force[0] / tip.hertz[0] << " of theory\n";
  EXPECT_NEAR(tip.force[0] / tip.hertz[0], 1.0, 0.25);
}

// The equilibrium a run settles into (held_tool_equilibrium, the hertz-run
// case) against a run: the CPU backend's Verlet steps lower a 2 cm sphere
// 4 mm (d/R 0.2) into the slab at 8 mm cells over 0.8 s and hold it 0.7 s,
// with drag to settle; the last reaction and the equilibrium's agree within
// 3 % (measured: 0.1 % for the layered surface contact and for point
// contact; the run's drag and tool speed leave a residue well below that).
// The small-strain solve of the same case (springs alone, point contact)
// is stiffer by more than 8 %: measured 1.09 / 0.97 of Hertz, the as-run
// penalty 20 000 N/m (within 0.2 % of its stiff limit: 0.9712 against
// 0.9726 at 200 000) and the small strain's 1000x the stiffest point. The
// springs' turning at the deformed shape, which the small strain leaves
// out, softens the run. An equilibrium solver that stopped early or took
// the linearised law fails one of the checks.
TEST(ValidationCases, AsRunIsTheEquilibriumARunSettlesIntoAndSofterThanSmallStrain) {
  const Vec3 slab(0.10, 0.08, 0.06);
  const double radius = 0.02, depth = 0.2 * radius, k = 2000;
  const TetMesh mesh = box(slab, kLiverCellSize);
  Material m = material(0.45);
  m.spring_damping_time = 2e-5;  // dampers that leave the 0.1 ms step stable; drag settles the run
  m.viscous_damping = 30;
  ModelOptions options;
  FixedSelector bottom;
  bottom.kind = FixedSelector::Kind::Box;
  bottom.min = Vec3(-1, -1, -1);
  bottom.max = Vec3(1, 1, 1e-6);
  options.fixed.push_back(bottom);
  const Model model = build_model(mesh, m, options, "test slab");
  const Vec3 from(0.05, 0.04, slab.z() + 1.05 * radius), to(0.05, 0.04, slab.z() + radius - depth);
  for (ToolContact contact : {ToolContact::Surface, ToolContact::Points}) {
    BackendTool tool;
    tool.present = true;
    tool.radius = radius;
    tool.contact_stiffness = k;
    tool.contact = contact;
    tool.hertz_layer = contact == ToolContact::Surface;
    const HeldToolEquilibrium settled = held_tool_equilibrium(model, tool, from, to);
    const auto run = make_cpu_backend(model, tool);
    TickRequest tick;
    tick.dt = 1e-4;
    tick.substeps = 10;
    tick.tool_active = true;
    Reaction last;
    for (int i = 0; i < 1500; ++i) {
      const double a = std::min(1.0, i / 800.0), b = std::min(1.0, (i + 1) / 800.0);
      tick.tool_from = from + a * (to - from);
      tick.tool_to = from + b * (to - from);
      last = run->tick(tick);
    }
    const char* name = contact == ToolContact::Surface ? "surface + layer" : "points";
    std::cout << name << ": run " << last.force.z() << " N, equilibrium " << settled.reaction.force.z() << " N in "
              << settled.steps << " steps\n";
    EXPECT_GT(settled.reaction.force.z(), 0) << name;
    EXPECT_NEAR(last.force.z() / settled.reaction.force.z(), 1.0, 0.03) << name;
  }
  Material springs;
  springs.young_modulus = 10e3;
  const IndentationResult small = sphere_indentation(mesh, springs, radius, {depth}, ToolContact::Points);
  const IndentationResult as_run =
      sphere_indentation(mesh, springs, radius, {depth}, ToolContact::Points, false, AsRun{20000});
  std::cout << "points, d/R 0.2: small strain " << small.force[0] / small.hertz[0] << ", as run "
            << as_run.force[0] / as_run.hertz[0] << " of Hertz\n";
  EXPECT_GT(small.force[0], 1.08 * as_run.force[0]);
}

// A capsule (R 5 mm) lying across a block 4 cm wide, pressed 1, 2 and 4 mm:
// a line load through the surface contact. Measured (nu 0.45): 0.312,
// 0.633, 1.294 N at 8 mm cells and 0.281, 0.568, 1.163 N at 5 mm.
TEST(ValidationCases, LineLoadOfACapsuleGrowsWithDepthPushesDownAndConvergesFromAbove) {
  const Vec3 block(0.08, 0.04, 0.03);
  const std::vector<double> depths{0.001, 0.002, 0.004};
  const LineLoadResult coarse = capsule_line_load(box(block, kLiverCellSize), material(0.45), 0.005, depths);
  const LineLoadResult fine = capsule_line_load(box(block, 0.005), material(0.45), 0.005, depths);
  EXPECT_NEAR(coarse.capsule_length, 0.04 + 4 * 0.005, 1e-6);
  for (const LineLoadResult* r : {&coarse, &fine}) {
    for (size_t i = 0; i < depths.size(); ++i) {
      const Vec3& f = r->force[i];
      std::cout << r->points << " points, d " << depths[i] * 1000 << " mm: force " << f.transpose() << " N, penalties "
                << r->contact_force[i].transpose() << " N, " << r->contacts[i] << " triangles\n";
      // Along -z, normal to the top: the sideways part is what the
      // irregular mesh adds (measured up to 5.3 % of the push); 10 %.
      EXPECT_LT(f.z(), 0);
      EXPECT_LT(std::hypot(f.x(), f.y()), 0.10 * -f.z()) << "d " << depths[i];
      EXPECT_GT(r->contacts[i], 0);
    }
    // A line contact's force grows about linearly with depth (2.02-2.05x
    // per doubling measured; a point contact like Hertz would give 2.8x):
    // 1.8-2.4x per doubling.
    for (size_t i = 1; i < depths.size(); ++i) {
      const double growth = r->force[i].z() / r->force[i - 1].z();
      EXPECT_GT(growth, 1.8) << "d " << depths[i];
      EXPECT_LT(growth, 2.4) << "d " << depths[i];
    }
  }
  // The surface contact converges from above (triangles a cell wide move as
  // planes; measured 8 mm / 5 mm 1.11 at every depth): a force that sank
  // between the points would be lower on the coarse mesh. Within 1-1.25.
  for (size_t i = 0; i < depths.size(); ++i) {
    const double ratio = coarse.force[i].z() / fine.force[i].z();
    EXPECT_GT(ratio, 1.0) << "d " << depths[i];
    EXPECT_LT(ratio, 1.25) << "d " << depths[i];
  }
}

// The same case with the capsule's line layer, as the backends apply it
// by default: at the liver's 8 mm cells within 15 % of the layered 5 mm
// mesh (measured 0.90 at 1 mm, 0.94 at 4 mm; docs/validation.md compares
// with 3.5 and 2.5 mm meshes, too slow for a test), and well below the
// plain contact's force there (measured 0.62-0.78 of it), which is 1.29-1.38
// times the 2.5 mm mesh's.
TEST(ValidationCases, LineLoadWithTheLineLayerIsWithinFifteenPercentOfAFinerMeshAtTheLiversCells) {
  const Vec3 block(0.08, 0.04, 0.03);
  const std::vector<double> depths{0.001, 0.004};
  const TetMesh coarse_mesh = box(block, kLiverCellSize);
  const LineLoadResult plain = capsule_line_load(coarse_mesh, material(0.45), 0.005, depths);
  const LineLoadResult coarse = capsule_line_load(coarse_mesh, material(0.45), 0.005, depths, true);
  const LineLoadResult fine = capsule_line_load(box(block, 0.005), material(0.45), 0.005, depths, true);
  for (size_t i = 0; i < depths.size(); ++i) {
    const double ratio = coarse.force[i].z() / fine.force[i].z();
    std::cout << "line load with the layer, d " << depths[i] * 1000 << " mm: 8 mm " << -coarse.force[i].z()
              << " N, 5 mm " << -fine.force[i].z() << " N (ratio " << ratio << "), without the layer at 8 mm "
              << -plain.force[i].z() << " N\n";
    EXPECT_NEAR(ratio, 1.0, 0.15) << "d " << depths[i];
    // The layer softens the coarse contact: measured 0.85 at d 4 mm on the
    // portable build's mesh, less on others.
    EXPECT_LT(coarse.force[i].z() / plain.force[i].z(), 0.90) << "d " << depths[i];
    EXPECT_LT(std::hypot(coarse.force[i].x(), coarse.force[i].y()), 0.10 * -coarse.force[i].z());
  }
}

}  // namespace
}  // namespace validation_cases_test
}  // namespace organsim
