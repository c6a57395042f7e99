// Per-label materials: the scenario's `materials` and `fixed: {label}`, the
// Model built from them (masses, springs that take each side's share on an
// interface, the volume term per point), a bi-material bar in tension against
// two moduli in series, and the combinations refused with a scenario error.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>

#include "core/model/model.h"
#include "core/model/stiffness.h"
#include "core/scenario/scenario.h"
#include "core/util/error.h"
#include "core/validation/static_solve.h"
#include "mesh_io_test_util.h"

namespace organsim {
namespace label_materials_test {
namespace {

using json = nlohmann::json;
using testing::error_message;

Scenario parse(const json& j) { return parse_scenario(j, "/data/scenes", "scene.json"); }

// A 10 x 2 x 2 cm bar along x, 20 x 4 x 4 cubes; label 1 for x < 5 cm, 2 beyond.
TetMesh two_label_bar() {
  TetMesh mesh = make_box_tet_mesh(Vec3(0, 0, 0), Vec3(0.1, 0.02, 0.02), 20, 4, 4);
  for (const Tet& t : mesh.tets) {
    const double x = (mesh.points[t[0]] + mesh.points[t[1]] + mesh.points[t[2]] + mesh.points[t[3]]).x() / 4;
    mesh.labels.push_back(x < 0.05 ? 1 : 2);
  }
  return mesh;
}

Material soft_tissue(double young_modulus) {
  Material m;
  m.young_modulus = young_modulus;
  m.poisson_ratio = 0.3;  // nodal volume term: per-point K
  m.density = 1000;
  return m;
}

ModelOptions held_at_x0(const std::vector<LabelMaterial>& materials) {
  ModelOptions o;
  FixedSelector plane;
  plane.kind = FixedSelector::Kind::Plane;
  plane.point = Vec3(1e-9, 0, 0);
  plane.normal = Vec3(-1, 0, 0);
  o.fixed = {plane};
  o.label_materials = materials;
  return o;
}

// Compliance (m/N) of the bar pulled along x at its free end by 1e-5 m.
double pulled_compliance(const Model& model) {
  StaticProblem problem;
  std::vector<int32_t> end;
  for (int32_t i = 0; i < model.npoint(); ++i) {
    if (model.rest_position[i].x() > 0.1 - 1e-9) {
      problem.prescribed.push_back({i, 0, 1e-5});
      end.push_back(i);
    }
  }
  const StaticSolution s = solve_static(model, problem);
  double force = 0;
  for (int32_t i : end) force += s.reaction[i].x();
  return 1e-5 / force;
}

TEST(LabelMaterials, BiMaterialBarMatchesTwoModuliInSeries) {
  const TetMesh bar = two_label_bar();
  const double soft = 3000, stiff = 30000;
  const auto compliance = [&](double e1, double e2) {
    return pulled_compliance(build_model(bar, soft_tissue(e1), held_at_x0({{{1}, soft_tissue(e1)}, {{2}, soft_tissue(e2)}})));
  };
  const double c_soft = compliance(soft, soft), c_stiff = compliance(stiff, stiff), c_both = compliance(soft, stiff);
  // Uniform bars: compliance ~ 1/E (the same mesh, the same clamping).
  EXPECT_NEAR(c_soft / c_stiff, stiff / soft, 1e-6 * stiff / soft);
  // In series, each half carries the same force: C = C_1/2 + C_2/2 with
  // each half's compliance its uniform bar's half. 5 %: the halves' lateral
  // contraction differs at the interface (nu the same, strain not), which a
  // 1D series model ignores. Interface springs taking only one side's
  // modulus would be off by ~15 % (their share of the bar's stiffness).
  EXPECT_NEAR(c_both, 0.5 * (c_soft + c_stiff), 0.05 * 0.5 * (c_soft + c_stiff));
  // Against the 1D theory with the moduli asked: L/2 / (E1 A) + L/2 / (E2 A),
  // within the mesh's own stiffness error (the uniform bar's ratio to 1D theory).
  const double area = 0.02 * 0.02, theory = 0.05 / (soft * area) + 0.05 / (stiff * area);
  const double mesh_factor = c_soft / (0.1 / (soft * area));
  EXPECT_NEAR(c_both / theory, mesh_factor, 0.05 * mesh_factor);
}

TEST(LabelMaterials, MassesAndInterfaceSpringsTakeEachSidesShare) {
  const TetMesh bar = two_label_bar();
  Material light = soft_tissue(3000), heavy = soft_tissue(3000);
  heavy.density = 3000;
  const Model m = build_model(bar, light, held_at_x0({{{1}, light}, {{2}, heavy}}));
  EXPECT_NEAR(m.total_mass(), 1000 * 0.1 * 0.02 * 0.02 / 2 + 3000 * 0.1 * 0.02 * 0.02 / 2, 1e-12);
  ASSERT_EQ(m.tet_label.size(), bar.tets.size());
  // Stiffer side: every spring wholly inside label 2 scales by 10, the
  // springs on the interface by between 1 and 10.
  Material stiff = soft_tissue(30000);
  const Model one = build_model(bar, light, held_at_x0({{{1, 2}, light}}));
  const Model two = build_model(bar, light, held_at_x0({{{1}, light}, {{2}, stiff}}));
  ASSERT_EQ(one.nspring(), two.nspring());
  int inside1 = 0, inside2 = 0, between = 0;
  for (int32_t s = 0; s < one.nspring(); ++s) {
    const double ratio = two.spring_k[s] / one.spring_k[s];
    const double xa = one.rest_position[one.spring_ends[s][0]].x(), xb = one.rest_position[one.spring_ends[s][1]].x();
    const double lo = std::min(xa, xb), hi = std::max(xa, xb), mid = 0.05, eps = 1e-9;
    if (hi < mid + eps && lo < mid - eps) {  // in label 1's cubes only
      EXPECT_NEAR(ratio, 1.0, 1e-12);
      ++inside1;
    } else if (lo > mid - eps && hi > mid + eps) {  // in label 2's cubes only
      EXPECT_NEAR(ratio, 10.0, 1e-9);
      ++inside2;
    } else {  // in the interface plane: tets on both sides
      EXPECT_GT(ratio, 1.0 + 1e-6);
      EXPECT_LT(ratio, 10.0 - 1e-6);
      ++between;
    }
    EXPECT_NEAR(two.spring_d[s] / two.spring_k[s], stiff.spring_damping_time, 1e-15);
  }
  EXPECT_GT(inside1, 0);
  EXPECT_GT(inside2, 0);
  EXPECT_GT(between, 0);
}

TEST(LabelMaterials, ScenarioMaterialsAndFixedByLabel) {
  const Scenario s = parse({{"mesh", {{"tet", "liver.mesh"}}},
                            {"materials", {{{"labels", {1}}, {"young_modulus", 3000}, {"poisson_ratio", 0.45}},
                                           {{"labels", {2, 3}}, {"young_modulus", 30000}, {"density", 1100}}}},
                            {"fixed", {{{"label", 3}}}}});
  ASSERT_EQ(s.materials.size(), 2u);
  EXPECT_EQ(s.materials[1].labels, (std::vector<int32_t>{2, 3}));
  EXPECT_EQ(s.materials[1].material.young_modulus, 30000);
  EXPECT_EQ(s.materials[1].material.density, 1100);
  EXPECT_EQ(s.material.young_modulus, 3000);  // the first, for what reads one material
  ASSERT_EQ(s.fixed.size(), 1u);
  EXPECT_EQ(s.fixed[0].kind, FixedSelector::Kind::Label);
  EXPECT_EQ(s.fixed[0].label, 3);
  const auto message = [&](const json& j) { return error_message([&] { parse(j); }); };
  EXPECT_NE(message({{"mesh", {{"tet", "a.mesh"}}}, {"material", json::object()}, {"materials", {{{"labels", {1}}}}}})
                .find("not both"),
            std::string::npos);
  EXPECT_NE(message({{"mesh", {{"tet", "a.mesh"}}}, {"materials", {{{"young_modulus", 1}}}}}).find("materials[0].labels: missing"),
            std::string::npos);
  EXPECT_NE(message({{"mesh", {{"tet", "a.mesh"}}}, {"materials", {{{"labels", {1}}, {"stiffness", 1}}}}})
                .find("materials[0].stiffness"),
            std::string::npos);
}

TEST(LabelMaterials, FixedByLabelHoldsEveryPointOfItsTets) {
  const TetMesh bar = two_label_bar();
  ModelOptions o;
  FixedSelector s;
  s.kind = FixedSelector::Kind::Label;
  s.label = 2;
  o.fixed = {s};
  const Model m = build_model(bar, soft_tissue(3000), o);
  for (int32_t i = 0; i < m.npoint(); ++i) {
    EXPECT_EQ(m.fixed[i] != 0, m.rest_position[i].x() >= 0.05 - 1e-9) << i;
  }
  s.label = 7;
  o.fixed = {s};
  EXPECT_NE(error_message([&] { build_model(bar, soft_tissue(3000), o); }).find("fixed[0].label: no tet has label 7"),
            std::string::npos);
}

TEST(LabelMaterials, RefusedCombinationsAreScenarioErrors) {
  const TetMesh bar = two_label_bar();
  const auto refusal = [&](const std::vector<LabelMaterial>& materials, const TetMesh& mesh) {
    try {
      build_model(mesh, materials.front().material, held_at_x0(materials));
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Scenario) << e.what();
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  Material a = soft_tissue(3000), b = soft_tissue(30000);
  EXPECT_NE(refusal({{{1}, a}}, bar).find("no entry for label 2"), std::string::npos);
  EXPECT_NE(refusal({{{1}, a}, {{1, 2}, b}}, bar).find("label 1 already has materials[0]"), std::string::npos);
  TetMesh unlabelled = bar;
  unlabelled.labels.clear();
  EXPECT_NE(refusal({{{1}, a}, {{2}, b}}, unlabelled).find("need a labelled mesh"), std::string::npos);
  b.viscous_damping = 5;
  EXPECT_NE(refusal({{{1}, a}, {{2}, b}}, bar).find("materials[1]: viscous_damping differs"), std::string::npos);
  b = soft_tissue(30000);
  b.poisson_ratio = 0.1;  // shear element on one side, volume term on the other
  EXPECT_NE(refusal({{{1}, a}, {{2}, b}}, bar).find("side of poisson_ratio 0.25"), std::string::npos);
  b = soft_tissue(30000);
  b.volume_formulation = VolumeFormulation::PerTet;
  EXPECT_NE(refusal({{{1}, a}, {{2}, b}}, bar).find("volume_formulation"), std::string::npos);
  Material springs;
  springs.spring_stiffness = 100;
  EXPECT_NE(refusal({{{1}, a}, {{2}, springs}}, bar).find("spring_stiffness"), std::string::npos);
}

}  // namespace
}  // namespace label_materials_test
}  // namespace organsim
