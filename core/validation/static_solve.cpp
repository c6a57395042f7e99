// GCC 12's AVX-512 intrinsics fill unused operands with _mm256_undefined_pd(),
// which -Wmaybe-uninitialized reports inside Eigen's dense matrix products
// (a known false positive; the Woodbury update below uses them). Before the
// first include: the header brings in Eigen.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include "core/validation/static_solve.h"

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <string>

#include "core/model/rest_stiffness.h"
#include "core/util/error.h"

namespace organsim {

std::vector<double> stiffness_diagonal(const Model& model) {
  std::vector<double> d(model.npoint(), 0.0);
  for (const auto& t : rest_stiffness(model))
    if (t.row() == t.col()) d[t.row() / 3] += t.value();
  return d;
}

namespace {

// The coordinates a problem holds: the Model's fixed points and its prescribed ones.
std::vector<uint8_t> held_coordinates(const Model& model, const std::vector<PrescribedDof>& prescribed) {
  const int32_t n = model.npoint();
  std::vector<uint8_t> held(3 * static_cast<size_t>(n), 0);
  for (int32_t p = 0; p < n; ++p)
    if (model.fixed[p]) held[3 * p] = held[3 * p + 1] = held[3 * p + 2] = 1;
  for (const PrescribedDof& d : prescribed) {
    if (d.point < 0 || d.point >= n || d.axis < 0 || d.axis > 2)
      throw Error(ErrorKind::Usage, "solve_static: prescribed point " + std::to_string(d.point) + " axis " +
                                        std::to_string(d.axis) + " out of range");
    held[3 * d.point + d.axis] = 1;
  }
  return held;
}

// A spring as a rank-one term: energy k/2 (a . u - target)^2 over the
// coordinates `dof` with coefficients `a`.
struct RankOne {
  std::vector<int32_t> dof;
  std::vector<double> a;
  double k = 0, target = 0;
};

std::vector<RankOne> rank_one_terms(const StaticProblem& problem) {
  std::vector<RankOne> terms;
  for (const PointSpring& s : problem.point_springs) {
    RankOne r{{}, {}, s.k, s.target};
    for (int i = 0; i < 3; ++i) r.dof.push_back(3 * s.point + i), r.a.push_back(s.direction[i]);
    terms.push_back(std::move(r));
  }
  for (const SurfaceSpring& s : problem.surface_springs) {
    RankOne r{{}, {}, s.k, s.target};
    for (int c = 0; c < 3; ++c)
      for (int i = 0; i < 3; ++i) r.dof.push_back(3 * s.points[c] + i), r.a.push_back(s.weights[c] * s.direction[i]);
    terms.push_back(std::move(r));
  }
  return terms;
}

}  // namespace

struct StaticSolver::Factor {
  std::vector<uint8_t> held;
  std::vector<int32_t> free_index;  // per coordinate, -1 where held
  int32_t nfree = 0;
  Eigen::SparseMatrix<double> K;  // all coordinates
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;  // of the free block
};

StaticSolver::StaticSolver(const Model& model, const std::vector<PrescribedDof>& held)
    : model_(model), factor_(std::make_unique<Factor>()) {
  Factor& f = *factor_;
  const int32_t ndof = 3 * model.npoint();
  f.held = held_coordinates(model, held);
  f.free_index.assign(ndof, -1);
  for (int32_t i = 0; i < ndof; ++i)
    if (!f.held[i]) f.free_index[i] = f.nfree++;
  const Triplets triplets = rest_stiffness(model);
  f.K = assemble(model, triplets);
  if (f.nfree == 0) return;
  Triplets free_triplets;
  free_triplets.reserve(triplets.size());
  for (int32_t col = 0; col < f.K.outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(f.K, col); it; ++it) {
      const int32_t r = f.free_index[it.row()], c = f.free_index[it.col()];
      if (r >= 0 && c >= 0) free_triplets.emplace_back(r, c, it.value());
    }
  Eigen::SparseMatrix<double> Kff(f.nfree, f.nfree);
  Kff.setFromTriplets(free_triplets.begin(), free_triplets.end());
  f.ldlt.compute(Kff);
  if (f.ldlt.info() != Eigen::Success || (f.ldlt.vectorD().array() <= 0).any())
    throw Error(ErrorKind::Numerical,
                "solve_static: the stiffness is singular: some rigid motion is not held by the supports");
}

StaticSolver::~StaticSolver() = default;

StaticSolution StaticSolver::solve(const StaticProblem& problem) const {
  const Factor& fa = *factor_;
  const int32_t n = model_.npoint(), ndof = 3 * n;
  if (held_coordinates(model_, problem.prescribed) != fa.held)
    throw Error(ErrorKind::Usage, "StaticSolver::solve: the problem holds other coordinates than were factored");
  Eigen::VectorXd u = Eigen::VectorXd::Zero(ndof), f = Eigen::VectorXd::Zero(ndof);
  for (const PrescribedDof& d : problem.prescribed)
    if (!model_.fixed[d.point]) u[3 * d.point + d.axis] = d.value;
  for (size_t p = 0; p < problem.load.size() && p < static_cast<size_t>(n); ++p) f.segment<3>(3 * p) = problem.load[p];
  const std::vector<RankOne> springs = rank_one_terms(problem);
  for (const RankOne& s : springs)
    for (size_t i = 0; i < s.dof.size(); ++i) f[s.dof[i]] += s.k * s.target * s.a[i];

  if (fa.nfree > 0) {
    // (K_ff + sum k a_f a_f^T) u_f = f_f - K_fh u_h - sum k (a_h . u_h) a_f.
    Eigen::VectorXd k_held = fa.K * u;
    for (const RankOne& s : springs) {
      double held_part = 0;
      for (size_t i = 0; i < s.dof.size(); ++i)
        if (fa.held[s.dof[i]]) held_part += s.a[i] * u[s.dof[i]];
      for (size_t i = 0; i < s.dof.size(); ++i) k_held[s.dof[i]] += s.k * held_part * s.a[i];
    }
    Eigen::VectorXd rhs(fa.nfree);
    for (int32_t i = 0; i < ndof; ++i)
      if (fa.free_index[i] >= 0) rhs[fa.free_index[i]] = f[i] - k_held[i];
    Eigen::VectorXd uf = fa.ldlt.solve(rhs);
    const int m = static_cast<int>(springs.size());
    if (m > 0) {
      // Woodbury: (K + A C A^T)^-1 r = y - Z (C^-1 + A^T Z)^-1 A^T y, y = K^-1 r, Z = K^-1 A.
      Eigen::MatrixXd A = Eigen::MatrixXd::Zero(fa.nfree, m);
      Eigen::VectorXd c_inv(m);
      for (int j = 0; j < m; ++j) {
        for (size_t i = 0; i < springs[j].dof.size(); ++i)
          if (fa.free_index[springs[j].dof[i]] >= 0) A(fa.free_index[springs[j].dof[i]], j) += springs[j].a[i];
        c_inv[j] = 1 / springs[j].k;
      }
      const Eigen::MatrixXd Z = fa.ldlt.solve(A);
      Eigen::MatrixXd S = A.transpose() * Z;
      S.diagonal() += c_inv;
      uf -= Z * S.ldlt().solve(A.transpose() * uf);
    }
    for (int32_t i = 0; i < ndof; ++i)
      if (fa.free_index[i] >= 0) u[i] = uf[fa.free_index[i]];
  }

  // The supports' reaction: (K + springs) u - f at the held coordinates.
  Eigen::VectorXd r = fa.K * u - f;
  for (const RankOne& s : springs) {
    double au = 0;
    for (size_t i = 0; i < s.dof.size(); ++i) au += s.a[i] * u[s.dof[i]];
    for (size_t i = 0; i < s.dof.size(); ++i) r[s.dof[i]] += s.k * au * s.a[i];
  }
  StaticSolution s;
  s.displacement.resize(n);
  s.reaction.assign(n, Vec3::Zero());
  for (int32_t p = 0; p < n; ++p) {
    s.displacement[p] = u.segment<3>(3 * p);
    for (int a = 0; a < 3; ++a)
      if (fa.held[3 * p + a]) s.reaction[p][a] = r[3 * p + a];
  }
  return s;
}

double StaticSolver::elastic_energy(const std::vector<Vec3>& u) const {
  Eigen::VectorXd x(3 * static_cast<Eigen::Index>(u.size()));
  for (size_t p = 0; p < u.size(); ++p) x.segment<3>(3 * static_cast<Eigen::Index>(p)) = u[p];
  return x.dot(factor_->K * x) / 2;
}

std::vector<Vec3> StaticSolver::elastic_force(const std::vector<Vec3>& u) const {
  Eigen::VectorXd x(3 * static_cast<Eigen::Index>(u.size()));
  for (size_t p = 0; p < u.size(); ++p) x.segment<3>(3 * static_cast<Eigen::Index>(p)) = u[p];
  const Eigen::VectorXd f = factor_->K * x;
  std::vector<Vec3> out(u.size());
  for (size_t p = 0; p < u.size(); ++p) out[p] = f.segment<3>(3 * static_cast<Eigen::Index>(p));
  return out;
}

StaticSolution solve_static(const Model& model, const StaticProblem& problem) {
  return StaticSolver(model, problem.prescribed).solve(problem);
}

}  // namespace organsim
