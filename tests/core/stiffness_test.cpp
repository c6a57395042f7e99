// The material -> stiffness rule (core/model/stiffness.h): its algebra, and
// that the lattice it builds carries the asked Lame constants.
#include <gtest/gtest.h>

#include "core/model/model.h"
#include "core/model/stiffness.h"
#include "core/util/error.h"

namespace organsim {
namespace stiffness_test {
namespace {

// The tet (0, e_x, e_y, e_z) * 1 cm.
TetMesh corner_tet() {
  TetMesh mesh;
  mesh.points = {Vec3(0, 0, 0), Vec3(0.01, 0, 0), Vec3(0, 0.01, 0), Vec3(0, 0, 0.01)};
  mesh.tets = {{0, 1, 2, 3}};
  return mesh;
}

TEST(Stiffness, PoissonRatioRuleGivesBackTheAskedConstants) {
  // Springs carry mu (lambda_s = mu), the volume term lambda - mu: the
  // effective solid must be exactly (E, nu). 1e-12: rounding only.
  for (double nu : {0.25, 0.3, 0.45, 0.49}) {
    Material m;
    m.young_modulus = 8000;
    m.poisson_ratio = nu;
    const EffectiveElasticity e = effective_elasticity(m);
    EXPECT_NEAR(e.young_modulus, 8000, 1e-12 * 8000) << nu;
    EXPECT_NEAR(e.poisson_ratio, nu, 1e-12) << nu;
    EXPECT_NEAR(e.shear_modulus, 8000 / (2 * (1 + nu)), 1e-9) << nu;
    EXPECT_GE(volume_term_modulus(m), 0) << nu;
  }
}

TEST(Stiffness, OldRuleIsUnchangedAndReportsItsEffectiveConstants) {
  Material m;
  m.young_modulus = 8000;
  EXPECT_DOUBLE_EQ(spring_modulus(m), 8000);
  EXPECT_DOUBLE_EQ(effective_elasticity(m).poisson_ratio, 0.25);
  EXPECT_DOUBLE_EQ(effective_elasticity(m).young_modulus, 8000);
  // The liver scenarios' material: springs 8 kPa plus a 20 kPa volume term
  // is a solid with lambda = 0.4 E + K, mu = 0.4 E.
  m.volume_modulus = 20000;
  const EffectiveElasticity e = effective_elasticity(m);
  EXPECT_NEAR(e.lame_lambda, 23200, 1e-9);
  EXPECT_NEAR(e.poisson_ratio, 23200.0 / (2 * (23200 + 3200)), 1e-12);
}

TEST(Stiffness, SpringsOfAUnitTetFollowTheFormula) {
  const TetMesh mesh = corner_tet();
  Material m;
  m.young_modulus = 1000;
  m.poisson_ratio = 0.4;
  const Model model = build_model(mesh, m, {});
  const double v = 1e-6 / 6;
  const double es = 2.5 * 1000 / (2 * 1.4);
  for (int32_t s = 0; s < model.nspring(); ++s) {
    const double r = model.spring_rest[s];
    EXPECT_NEAR(model.spring_k[s], es * v / (r * r), 1e-9 * model.spring_k[s]);
  }
  // With a Poisson ratio the volume term is nodal: k_a V_a^r = K_v, V_a^r = V / 4.
  ASSERT_TRUE(model.has_nodal_volume());
  for (int32_t a = 0; a < 4; ++a) {
    EXPECT_NEAR(model.point_rest_volume[a], v / 4, 1e-12 * v);
    EXPECT_NEAR(model.point_volume_k[a] * v / 4, volume_term_modulus(m), 1e-9 * volume_term_modulus(m));
  }
  m.volume_formulation = VolumeFormulation::PerTet;
  const Model per_tet = build_model(mesh, m, {});
  ASSERT_TRUE(per_tet.has_volume() && !per_tet.has_nodal_volume());
  EXPECT_NEAR(per_tet.tet_k[0] * v, volume_term_modulus(m), 1e-9 * volume_term_modulus(m));
}

TEST(Stiffness, PoissonRatioOutOfRangeOrWithVolumeModulusIsRefused) {
  const TetMesh mesh = corner_tet();
  Material m;
  m.poisson_ratio = 0.5;
  EXPECT_THROW(build_model(mesh, m, {}), Error);
  m.poisson_ratio = -0.01;
  try {
    build_model(mesh, m, {});
    FAIL() << "poisson_ratio -0.01 accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Scenario);
    EXPECT_NE(std::string(e.what()).find("expected a number in [0, 0.5)"), std::string::npos) << e.what();
  }
  m.poisson_ratio = 0.2;  // below 1/4: the shear element, no volume term
  EXPECT_TRUE(build_model(mesh, m, {}).has_shear_element());
  m.poisson_ratio = 0.3;
  m.volume_modulus = 100;
  try {
    build_model(mesh, m, {});
    FAIL() << "poisson_ratio with volume_modulus accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Scenario);
    EXPECT_NE(std::string(e.what()).find("poisson_ratio or volume_modulus"), std::string::npos);
  }
}

}  // namespace
}  // namespace stiffness_test
}  // namespace organsim
