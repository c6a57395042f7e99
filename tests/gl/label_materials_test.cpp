// The GL backend on a model with per-label materials (a stiff, denser half
// next to a soft one: per-point masses, springs that take each side's share
// on the interface, a nodal volume term or a shear element whose stiffness
// changes across it) against the double CPU reference: the force of one
// step, and a trajectory.
#include <gtest/gtest.h>

#include "core/gl/gl_backend.h"
#include "core/sim/cpu_backend.h"
#include "gl_test_scenes.h"

namespace organsim {
namespace label_materials_test {
namespace {

constexpr double kDt = 1e-4;  // s

// The poisson_box (0.1 x 0.1 x 0.05 m, 5 x 5 x 3 cubes, bottom fixed), label
// 1 for x < 0.06 m and label 2 beyond, E 3 and 30 kPa, density 1000 and
// 1500 kg/m^3, both with Poisson ratio nu: from 1/4 up the nodal volume
// term, below it the smoothed shear element.
Model two_label_box(double nu) {
  TetMesh mesh = make_box_tet_mesh(Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.05), 5, 5, 3);
  for (const Tet& t : mesh.tets) {
    const double x = (mesh.points[t[0]] + mesh.points[t[1]] + mesh.points[t[2]] + mesh.points[t[3]]).x() / 4;
    mesh.labels.push_back(x < 0.06 ? 1 : 2);
  }
  Material soft;
  soft.young_modulus = 3000;
  soft.poisson_ratio = nu;
  soft.density = 1000;
  Material stiff = soft;
  stiff.young_modulus = 30000;
  stiff.density = 1500;
  ModelOptions options = testing::fixed_bottom_options(Vec3(0, 0, -9.81));
  options.label_materials = {{{1}, soft}, {{2}, stiff}};
  return build_model(mesh, soft, options, "two-label box");
}

TEST(GlLabelMaterials, ForceMatchesTheReference) {
  for (const double nu : {0.45, 0.2}) {
    const Model model = two_label_box(nu);
    ASSERT_FALSE(model.tet_material.empty());
    ASSERT_EQ(model.has_nodal_volume(), nu > 0.25);
    ASSERT_EQ(model.has_shear_element(), nu < 0.25);
    for (const int32_t threads_per_point : {1, 3}) {
      SCOPED_TRACE("nu " + std::to_string(nu) + ", threads per point " + std::to_string(threads_per_point));
      const double error =
          gl_test::one_substep_force_error(model, gl_test::moving_state(model, kDt), kDt, threads_per_point);
      std::cout << "two labels, nu " << nu << ", " << threads_per_point
                << " invocation(s) per point: max |f_gl - f_ref| / max |f_ref| = " << error << "\n";
      // Float against double, as in nodal_volume_test.cpp and
      // shear_element_test.cpp (~1e-6 from rounding); a material taken from
      // the wrong side of the interface changes forces there by up to 10x.
      EXPECT_LT(error, 1e-5);
    }
  }
}

// 100 ticks of 10 steps of the box released from a 2 % squeeze under
// gravity: GL against the double CPU backend within 1e-5 of the bounding-box
// diagonal (parity_test.cpp's tolerance: float round-off random-walks to
// ~1e-6 of it; a wrong mass or stiffness on one side moves points by
// millimetres).
TEST(GlLabelMaterials, TrajectoryMatchesTheCpuReference) {
  for (const double nu : {0.45, 0.2}) {
    SCOPED_TRACE("nu " + std::to_string(nu));
    const Model model = two_label_box(nu);
    const gl_test::TrajectoryDifference d = gl_test::cpu_and_gl_from(model, gl_test::squeezed_box(model), kDt, 100);
    const double diagonal = gl_test::bbox_diagonal(model);
    std::cout << "two labels, nu " << nu << ": max |x_gl - x_cpu| / diagonal = " << d.worst / diagonal
              << ", motion " << d.motion << " m\n";
    ASSERT_GT(d.motion, 1e-4);
    EXPECT_LT(d.worst, 1e-5 * diagonal);
  }
}

}  // namespace
}  // namespace label_materials_test
}  // namespace organsim
