// The implicit system's product on every SIMD target this CPU runs
// (core/sim/implicit_gather_simd.h) against its scalar code, the
// reference: the same terms in the same order, so they differ by rounding
// only, for every element term, sutures (one slack), the contact's blocks,
// and point and tet counts that leave items past the last whole group; on two
// threads bit-identical to one; and implicit Euler runs on it as on the
// scalar product.
#include <gtest/gtest.h>

#include <random>

#include "core/model/model_rebuild.h"
#include "core/sim/implicit_system.h"
#include "core/sim/reference_backend.h"
#include "tests/core/cpu_kernel_test_util.h"

namespace organsim {
namespace implicit_gather_simd_test {
namespace {

using testing::VolumeTerm;

// Every element term the system linearises, and none.
constexpr VolumeTerm kTerms[] = {VolumeTerm::None, VolumeTerm::PerTet, VolumeTerm::Nodal, VolumeTerm::Shear02,
                                 VolumeTerm::ShearPerTet};

// A jittered box of cells^3 cells with three sutures across it, the first
// tied long enough to be slack at the linearisation. 3 cells: 64 points (8
// whole groups) and 162 tets (20 whole groups and 2 past them); 4 cells:
// 125 points (15 whole groups and 5 past them) and 384 tets.
Model sutured_box(VolumeTerm volume, int cells) {
  const Model box = testing::random_model(2, cells, volume, true);
  const int32_t n = box.npoint();
  std::vector<Suture> sutures;
  for (const auto& [a, b, slack] :
       {std::tuple{3, n - 5, true}, std::tuple{10, n - 27, false}, std::tuple{40, n - 48, false}}) {
    Suture s;
    s.ends = {std::min(a, b), std::max(a, b)};
    s.k = 30;
    const double distance = (box.rest_position[a] - box.rest_position[b]).norm();
    s.length = slack ? 2 * distance : 0.5 * distance;
    sutures.push_back(s);
  }
  return add_sutures(box, sutures);
}

std::vector<std::pair<VolumeTerm, int>> terms_and_boxes() {
  std::vector<std::pair<VolumeTerm, int>> out;
  for (const VolumeTerm volume : kTerms)
    for (const int cells : {3, 4}) out.emplace_back(volume, cells);
  return out;
}

struct State {
  std::vector<Vec3> x, v;
  Eigen::VectorXd p;
  std::vector<ContactBlock> contact;
};

State random_state(const Model& m) {
  State s;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  s.x = m.rest_position;
  s.v.resize(m.npoint());
  for (int32_t i = 0; i < m.npoint(); ++i)
    s.x[i] += 5e-4 * Vec3(u(rng), u(rng), u(rng)), s.v[i] = Vec3(u(rng), u(rng), u(rng));
  s.p.resize(3 * m.npoint());
  for (auto& c : s.p) c = u(rng);
  ContactBlock triangle;
  triangle.point = {3, 7, m.npoint() - 4};  // one corner past the whole groups with 4 cells
  triangle.w = {0.2, 0.3, 0.5};
  triangle.k = 50 * Eigen::Matrix3d::Identity();
  ContactBlock point;
  point.point = {60, -1, -1};
  point.w = {1, 0, 0};
  point.k = Eigen::Vector3d(0.3, 0.2, 0.9).normalized() * Eigen::Vector3d(0.3, 0.2, 0.9).normalized().transpose() * 80;
  s.contact = {triangle, point};
  return s;
}

Eigen::VectorXd product(const Model& m, const State& s, const std::optional<SimdTarget>& target, int32_t threads,
                        double m_coef, double alpha, double beta) {
  ImplicitSystem system(m, threads, target);
  system.linearise(s.x, s.v, 0, s.contact);
  Eigen::VectorXd out;
  system.apply(m_coef, alpha, beta, s.p, out);
  return out;
}

// (m_coef, alpha, beta): a step's matrix (h = 2 ms), its K alone (a step's
// K v), its M + h D alone (implicit damping's matrix).
constexpr std::array<double, 3> kCoefficients[] = {{1, 2e-3, 4e-6}, {0, 0, 1}, {1, 2e-3, 0}};

TEST(ImplicitGatherSimd, EveryTargetsProductEqualsTheScalarGatherToRounding) {
  // Both boxes leave items past the last whole group: tets with 3 cells, points with 4.
  ASSERT_NE(sutured_box(VolumeTerm::PerTet, 3).ntet() % kGatherGroup, 0);
  ASSERT_NE(sutured_box(VolumeTerm::PerTet, 4).npoint() % kGatherGroup, 0);
  for (const auto& [volume, cells] : terms_and_boxes()) {
    SCOPED_TRACE(std::string(testing::volume_term_name(volume)) + ", " + std::to_string(cells) + " cells");
    const Model m = sutured_box(volume, cells);
    const State s = random_state(m);
    for (const auto& [m_coef, alpha, beta] : kCoefficients) {
      const Eigen::VectorXd reference = product(m, s, std::nullopt, 1, m_coef, alpha, beta);
      ASSERT_GT(reference.norm(), 0);
      for (const SimdTarget& target : simd_targets_supported()) {
        const Eigen::VectorXd simd = product(m, s, target, 1, m_coef, alpha, beta);
        // Rounding of sums of a few tens of terms, with fused multiply-adds
        // where the target has them: some 1e-15 of the largest entry; a
        // missing or misplaced term is of the order of the entries.
        const double scale = reference.lpNorm<Eigen::Infinity>();
        for (int32_t i = 0; i < reference.size(); ++i)
          ASSERT_NEAR(simd[i], reference[i], 1e-12 * scale)
              << target.name << ", coordinate " << i << ", coefficients " << m_coef << " " << alpha << " " << beta;
      }
    }
  }
}

TEST(ImplicitGatherSimd, TwoThreadsAreBitIdenticalToOne) {
  const SimdTarget best = default_simd_target();
  for (const auto& [volume, cells] : terms_and_boxes()) {
    const Model m = sutured_box(volume, cells);
    const State s = random_state(m);
    const Eigen::VectorXd one = product(m, s, best, 1, 1, 2e-3, 4e-6), two = product(m, s, best, 2, 1, 2e-3, 4e-6);
    EXPECT_TRUE(std::equal(one.data(), one.data() + one.size(), two.data())) << testing::volume_term_name(volume);
  }
}

// Thirty implicit Euler steps of 2 ms of a box pressed by a sphere (its
// contact blocks in the system) on the best target's product and on the
// scalar one: the same solves up to CG's tolerance (relative residual
// 1e-8 here, so that the solves' own error stays far below the bound).
TEST(ImplicitGatherSimd, ImplicitEulerOnTheSimdProductFollowsTheScalarOne) {
  for (const VolumeTerm volume : {VolumeTerm::PerTet, VolumeTerm::Nodal, VolumeTerm::Shear02}) {
    SCOPED_TRACE(testing::volume_term_name(volume));
    const Model m = testing::random_model(4, 4, volume, true);
    BackendTool tool;
    tool.present = true;
    tool.radius = 0.01;
    tool.contact_stiffness = 300;
    tool.contact = ToolContact::Points;
    TickRequest request;
    request.dt = 2e-3;
    request.substeps = 1;
    request.tool_active = true;
    std::vector<std::vector<Vec3>> positions;
    for (const bool simd : {false, true}) {
      ImplicitOptions options;
      options.cg_tolerance = 1e-8;
      if (simd) options.simd_product = default_simd_target();
      auto backend = make_reference_backend(m, tool, Integrator::ImplicitEuler, options, 1);
      const std::string device = backend->device();
      EXPECT_NE(device.find(simd ? "simd (" + default_simd_target().name + ") product" : "(reference, double"),
                std::string::npos)
          << device;
      for (int step = 0; step < 30; ++step) {
        request.tool_from = request.tool_to = Vec3(0.02, 0.02, testing::kSize + 0.01 - 1e-4 * step);
        backend->tick(request);
      }
      positions.emplace_back();
      backend->positions(positions.back());
    }
    double moved = 0, apart = 0;
    for (int32_t i = 0; i < m.npoint(); ++i) {
      moved = std::max(moved, (positions[0][i] - m.rest_position[i]).norm());
      apart = std::max(apart, (positions[1][i] - positions[0][i]).norm());
    }
    ASSERT_GT(moved, 1e-4);
    // Each solve's error is below 1e-8 of its right-hand side, so thirty of
    // them part the runs by far less than 1e-6 of the motion; a wrong product
    // moves them apart by a fraction of it.
    EXPECT_LT(apart, 1e-6 * moved) << "moved " << moved << " m, apart " << apart << " m";
  }
}

}  // namespace
}  // namespace implicit_gather_simd_test
}  // namespace organsim
