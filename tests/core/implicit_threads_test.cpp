// The implicit solve on several threads (core/sim/implicit_system.h,
// conjugate_gradient.h): its products, its diagonal blocks, CG's own dot
// products and a whole run of implicit Euler steps are bit-identical to one
// thread's, for every element term, because each sum runs in an order the
// thread count does not change.
#include <gtest/gtest.h>

#include <random>

#include "core/sim/conjugate_gradient.h"
#include "core/sim/implicit_system.h"
#include "core/sim/reference_backend.h"
#include "core/util/error.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace implicit_threads_test {
namespace {

// The three element terms: the per-tet volume term (volume_modulus), the
// nodal one (poisson_ratio 0.45) and the shear element with its damper
// (poisson_ratio 0.2).
std::vector<Material> materials() {
  std::vector<Material> out(3);
  for (Material& m : out) {
    m.density = 1000;
    m.young_modulus = 5000;
    m.spring_damping_time = 0.005;
    m.viscous_damping = 2;
  }
  out[0].volume_modulus = 20000;
  out[1].poisson_ratio = 0.45;
  out[2].poisson_ratio = 0.2;
  return out;
}

Model box(const Material& material) {
  return build_model(make_box_tet_mesh(Vec3::Zero(), Vec3::Constant(0.04), 4, 4, 4), material,
                     testing::fixed_bottom_options());
}

bool same_bits(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() && std::equal(a.data(), a.data() + a.size(), b.data());
}

TEST(ImplicitSystem, ProductsAndDiagonalBlocksOnSeveralThreadsAreBitIdenticalToOne) {
  const std::vector<Material> all = materials();
  for (size_t which = 0; which < all.size(); ++which) {
    const Model m = box(all[which]);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<Vec3> x = m.rest_position, v(m.npoint());
    for (int32_t i = 0; i < m.npoint(); ++i) x[i] += 5e-4 * Vec3(u(rng), u(rng), u(rng)), v[i] = Vec3(u(rng), u(rng), u(rng));
    Eigen::VectorXd p(3 * m.npoint());
    for (auto& c : p) c = u(rng);
    ContactBlock contact;
    contact.point = {3, 7, 11};
    contact.w = {0.2, 0.3, 0.5};
    contact.k = 50 * Eigen::Matrix3d::Identity();
    Eigen::VectorXd one_product;
    std::vector<Eigen::Matrix3d> one_blocks;
    for (const int32_t threads : {1, 2, 3}) {
      ImplicitSystem system(m, threads);
      system.linearise(x, v, 0, {contact});
      Eigen::VectorXd product;
      std::vector<Eigen::Matrix3d> blocks;
      system.apply(1, 2e-3, 4e-6, p, product);
      system.diagonal_blocks(1, 2e-3, 4e-6, blocks);
      if (threads == 1) {
        one_product = product, one_blocks = blocks;
        ASSERT_GT(product.norm(), 0);
        continue;
      }
      EXPECT_TRUE(same_bits(product, one_product)) << "threads " << threads << ", material " << which;
      ASSERT_EQ(blocks.size(), one_blocks.size());
      for (size_t i = 0; i < blocks.size(); ++i)
        ASSERT_TRUE(blocks[i] == one_blocks[i]) << "point " << i << ", threads " << threads;
    }
  }
}

// Forty implicit Euler steps of a box pressed by a sphere (its contact in
// the system), on one thread and on two: the same positions to the bit.
TEST(ImplicitEuler, TwoThreadsStepBitIdenticalToOne) {
  const std::vector<Material> all = materials();
  for (size_t which = 0; which < all.size(); ++which) {
    const Model m = box(all[which]);
    BackendTool tool;
    tool.present = true;
    tool.radius = 0.015;
    tool.contact_stiffness = 300;
    tool.contact = ToolContact::Points;
    TickRequest request;
    request.dt = 2e-3;
    request.substeps = 1;
    request.tool_active = true;
    std::vector<std::vector<Vec3>> positions;
    std::vector<std::string> devices;
    for (const int32_t threads : {1, 2}) {
      auto backend = make_reference_backend(m, tool, Integrator::ImplicitEuler, {}, threads);
      for (int step = 0; step < 40; ++step) {
        // Down from above the top face, 4 mm into it by the last step.
        request.tool_from = request.tool_to = Vec3(0.02, 0.02, 0.04 + 0.015 - 1e-4 * step);
        backend->tick(request);
      }
      positions.emplace_back();
      backend->positions(positions.back());
      devices.push_back(backend->device());
    }
    EXPECT_NE(positions[0], m.rest_position);
    EXPECT_EQ(positions[0], positions[1]) << "material " << which;
    EXPECT_NE(devices[0].find("1 thread,"), std::string::npos) << devices[0];
    EXPECT_NE(devices[1].find("2 threads,"), std::string::npos) << devices[1];
  }
}

// CG alone on a system of 9000 coordinates (several of its blocks): a
// tridiagonal SPD matrix, a third of the coordinates held, Jacobi
// preconditioned. On two and three threads the same bits as on one, and
// converged to its tolerance.
TEST(ConjugateGradient, SeveralThreadsSolveBitIdenticalToOne) {
  const Eigen::Index n = 9000;
  const LinearOperator a = [n](const Eigen::VectorXd& x, Eigen::VectorXd& y) {
    y.resize(n);
    for (Eigen::Index i = 0; i < n; ++i)
      y[i] = (3 + 0.001 * (i % 7)) * x[i] - (i > 0 ? x[i - 1] : 0) - (i + 1 < n ? x[i + 1] : 0);
  };
  const LinearOperator jacobi = [](const Eigen::VectorXd& r, Eigen::VectorXd& z) { z = r / 3; };
  Eigen::VectorXd b(n), free(n);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1, 1);
  for (Eigen::Index i = 0; i < n; ++i) b[i] = u(rng), free[i] = i % 3 == 1 ? 0 : 1;
  Eigen::VectorXd one;
  for (const int32_t threads : {1, 2, 3}) {
    CgWorkspace work;
    work.threads = threads;
    Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
    const CgResult r = conjugate_gradient(a, jacobi, b, free, 1e-10, 500, x, work);
    ASSERT_TRUE(r.converged) << threads << " threads, residual " << r.residual;
    Eigen::VectorXd ax;
    a(x, ax);
    EXPECT_LE((ax - b).cwiseProduct(free).norm(), 1e-9 * b.cwiseProduct(free).norm());
    if (threads == 1) {
      one = x;
      continue;
    }
    EXPECT_TRUE(same_bits(x, one)) << threads << " threads";
  }
}

TEST(ImplicitEuler, ThreadsBelowOneAreRefused) {
  const Model m = box(materials()[1]);
  try {
    make_reference_backend(m, {}, Integrator::ImplicitEuler, {}, 0);
    FAIL() << "threads 0 accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("threads must be >= 1"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace implicit_threads_test
}  // namespace organsim
