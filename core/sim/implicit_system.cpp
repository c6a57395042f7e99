#include "core/sim/implicit_system.h"

#include <omp.h>

#include <algorithm>
#include <limits>
#include <type_traits>

#include "core/model/rest_stiffness.h"
#include "core/physics/force_law.h"
#include "core/util/error.h"

namespace organsim {

namespace {

ImplicitSystem::ShearMatrix row_major(const Model& model, const Triplets& t) {
  return ImplicitSystem::ShearMatrix(assemble(model, t));
}

Eigen::Map<const Eigen::Vector3d> at(const Eigen::VectorXd& v, int32_t p) { return Eigen::Map<const Eigen::Vector3d>(v.data() + 3 * p); }
Eigen::Map<Eigen::Vector3d> at(Eigen::VectorXd& v, int32_t p) { return Eigen::Map<Eigen::Vector3d>(v.data() + 3 * p); }

// One incidence (point i's rows start[i] .. start[i + 1]) laid out as the
// SIMD gather's slot rows (implicit_gather_simd.h): each group's first row
// (groups + 1) and the incidence row each slot holds (-1: padding).
void slot_rows(int32_t groups, const std::vector<int32_t>& start, std::vector<int32_t>& group_row,
               std::vector<int32_t>& slot_row) {
  group_row.assign(static_cast<size_t>(groups) + 1, 0);
  for (int32_t g = 0; g < groups; ++g) {
    int32_t rows = 0;
    for (int32_t i = kGatherGroup * g; i < kGatherGroup * (g + 1); ++i) rows = std::max(rows, start[i + 1] - start[i]);
    group_row[g + 1] = group_row[g] + rows;
  }
  slot_row.assign(static_cast<size_t>(kGatherGroup) * group_row[groups], -1);
  for (int32_t g = 0; g < groups; ++g)
    for (int32_t r = 0; r < group_row[g + 1] - group_row[g]; ++r)
      for (int32_t lane = 0; lane < kGatherGroup; ++lane) {
        const int32_t i = kGatherGroup * g + lane;
        if (r < start[i + 1] - start[i])
          slot_row[static_cast<size_t>(kGatherGroup) * (group_row[g] + r) + lane] = start[i] + r;
      }
}

}  // namespace

ImplicitSystem::ImplicitSystem(const Model& model, int32_t threads, const std::optional<SimdTarget>& product)
    : model_(model), threads_(std::max<int32_t>(threads, 1)), patch_row_(static_cast<size_t>(threads_)) {
  if (model.has_shear_element()) {
    shear_k_ = row_major(model, rest_stiffness(model, RestTerms::ShearElement));
    shear_d_ = row_major(model, rest_damping(model, RestTerms::ShearElement));
  }
  const int32_t n = model.npoint();
  // Counting sorts by point: each row lists its elements in element order.
  const auto incidence = [n](int32_t nelement, int arity, const auto& point_of, bool with_corner,
                             std::vector<int32_t>& start, std::vector<int32_t>& entry) {
    start.assign(n + 1, 0);
    for (int32_t e = 0; e < nelement; ++e)
      for (int c = 0; c < arity; ++c) ++start[point_of(e, c) + 1];
    for (int32_t i = 0; i < n; ++i) start[i + 1] += start[i];
    entry.resize(static_cast<size_t>(start[n]));
    std::vector<int32_t> fill(start.begin(), start.end() - 1);
    for (int32_t e = 0; e < nelement; ++e)
      for (int c = 0; c < arity; ++c) entry[fill[point_of(e, c)]++] = with_corner ? arity * e + c : e;
  };
  incidence(
      model.nspring(), 2, [&](int32_t s, int c) { return model.spring_ends[s][c]; }, true, spring_start_,
      spring_of_point_);
  spring_other_.resize(spring_of_point_.size());
  for (size_t k = 0; k < spring_of_point_.size(); ++k)
    spring_other_[k] = model.spring_ends[spring_of_point_[k] >> 1][1 - (spring_of_point_[k] & 1)];
  if (model.has_volume())
    incidence(model.ntet(), 4, [&](int32_t t, int c) { return model.tet_points[t][c]; }, true, corner_start_,
              corner_of_point_);
  if (model.has_nodal_volume()) {
    patch_start_.assign(n + 1, 0);
    patch_slot_.resize(4 * corner_of_point_.size());
    std::vector<int32_t> patch;
    for (int32_t i = 0; i < n; ++i) {
      patch.clear();
      for (int32_t k = corner_start_[i]; k < corner_start_[i + 1]; ++k)
        for (int j = 0; j < 4; ++j) {
          const int32_t a = model.tet_points[corner_of_point_[k] >> 2][j];
          auto found = std::find(patch.begin(), patch.end(), a);
          if (found == patch.end()) found = patch.insert(patch.end(), a);
          if (patch.size() > std::numeric_limits<uint16_t>::max())
            throw Error(ErrorKind::Input, "implicit Euler: point " + std::to_string(i) + " shares tets with over " +
                                              std::to_string(std::numeric_limits<uint16_t>::max()) + " points");
          patch_slot_[4 * static_cast<size_t>(k) + j] = static_cast<uint16_t>(found - patch.begin());
        }
      patch_point_.insert(patch_point_.end(), patch.begin(), patch.end());
      patch_start_[i + 1] = static_cast<int32_t>(patch_point_.size());
    }
  }
  tet_term_.resize(model.has_volume() ? model.ntet() + 1 : 0);
  node_term_.resize(model.has_nodal_volume() ? n : 0);
  if (product) {
    simd_ = &implicit_gather_for(*product);
    GatherStreams& s = streams_;
    s.groups = n / kGatherGroup;
    // A padding slot's other end is its own point (dp = 0), its corner the zero coefficient tet_term_[ntet].
    std::vector<int32_t> slot_row;
    slot_rows(s.groups, spring_start_, s.spring_row, slot_row);
    const size_t springs = slot_row.size();
    s.other3.resize(springs);
    slot_spring_.resize(springs);
    for (int32_t g = 0; g < s.groups; ++g)
      for (size_t k = size_t{kGatherGroup} * s.spring_row[g]; k < size_t{kGatherGroup} * s.spring_row[g + 1]; ++k) {
        const int32_t row = slot_row[k];
        const int32_t self = kGatherGroup * g + static_cast<int32_t>(k % kGatherGroup);
        s.other3[k] = 3 * (row >= 0 ? spring_other_[row] : self);
        slot_spring_[k] = row >= 0 ? spring_of_point_[row] >> 1 : model.nspring();
      }
    for (auto* stream : {&s.u[0], &s.u[1], &s.u[2], &s.axial, &s.transverse, &s.damper}) stream->assign(springs, 0);
    if (model.has_volume()) {
      slot_rows(s.groups, corner_start_, s.corner_row, slot_row);
      const size_t corners = slot_row.size();
      s.corner_tet.resize(corners);
      slot_corner_.resize(corners);
      for (size_t k = 0; k < corners; ++k) {
        slot_corner_[k] = slot_row[k] >= 0 ? corner_of_point_[slot_row[k]] : 4 * model.ntet();
        s.corner_tet[k] = slot_corner_[k] >> 2;
      }
      for (auto& stream : s.gradient) stream.assign(corners, 0);
      s.tet_groups = model.ntet() / kGatherGroup;
      const size_t tets = static_cast<size_t>(kGatherGroup) * s.tet_groups;
      for (int c = 0; c < 4; ++c) {
        s.tet_point[c].resize(tets);
        for (size_t e = 0; e < tets; ++e) s.tet_point[c][e] = model.tet_points[e][c];
        for (auto& stream : s.tet_gradient[c]) stream.resize(tets);
      }
    } else {
      s.corner_row.assign(static_cast<size_t>(s.groups) + 1, 0);
    }
  }
}

template <class Body>
void ImplicitSystem::for_each(int32_t n, const Body& body) const {
  // A body that takes a second argument gets its thread's slot (0 ..
  // threads_ - 1) for per-thread scratch.
  const auto call = [&body](int32_t i, int slot) {
    if constexpr (std::is_invocable_v<Body, int32_t, int>)
      body(i, slot);
    else
      body(i);
  };
  if (threads_ > 1 && !omp_in_parallel()) {
#pragma omp parallel for schedule(static) num_threads(threads_)
    for (int32_t i = 0; i < n; ++i) call(i, omp_get_thread_num());
  } else {
    for (int32_t i = 0; i < n; ++i) call(i, 0);
  }
}

template <class Simd, class Scalar>
void ImplicitSystem::for_each_group(int32_t n, int32_t groups, const Simd& simd, const Scalar& scalar) const {
  // Blocks of groups, so that a call through the target's pointer covers some work.
  constexpr int32_t kBlock = 16;
  for_each((groups + kBlock - 1) / kBlock, [&](int32_t b) { simd(kBlock * b, std::min(groups, kBlock * (b + 1))); });
  const int32_t first = kGatherGroup * groups;
  for_each(n - first, [&](int32_t i) { scalar(first + i); });
}

void ImplicitSystem::linearise(const std::vector<Vec3>& x, const std::vector<Vec3>& v, double t,
                               const std::vector<ContactBlock>& contact) {
  const Model& m = model_;
  springs_.resize(static_cast<size_t>(m.nspring()) + 1);  // the last stays zero: the SIMD slots' padding
  for_each(m.nspring(), [&](int32_t s) {
    springs_[s] = {};
    const auto [a, b] = m.spring_ends[s];
    const Vec3 l = x[b] - x[a];
    const double length = l.norm();
    if (!(length > 0)) return;  // coincident ends: no direction, no force, no stiffness
    const Vec3 u = l / length;
    const double rest = m.spring_rest_at(s, t);
    double tension = force_law::spring_tension(m.spring_k[s], m.spring_d[s], length, rest, (v[b] - v[a]).dot(u));
    // A slack suture (or one its damper would turn into a push) exerts nothing, so it stiffens nothing.
    if (s >= m.first_suture() && force_law::suture_tension(tension, length, rest) == 0) return;
    const double transverse = force_law::spring_transverse_stiffness(tension, length);
    springs_[s] = {u, m.spring_k[s] - transverse, transverse, m.spring_d[s]};
  });
  volume_gradient_.resize(m.has_volume() ? m.ntet() + 1 : 0);  // the last stays zero, as springs_'s
  if (m.has_volume())
    for_each(m.ntet(), [&](int32_t e) {
      const Tet& tet = m.tet_points[e];
      const Vec3 e1 = x[tet[1]] - x[tet[0]], e2 = x[tet[2]] - x[tet[0]], e3 = x[tet[3]] - x[tet[0]];
      Vec3 g1, g2, g3;  // 6 dV/dx_k
      force_law::tet_volume_gradients6(e1, e2, e3, g1, g2, g3);
      volume_gradient_[e] = {-(g1 + g2 + g3) / 6, g1 / 6, g2 / 6, g3 / 6};
    });
  // Copied into each point's incidence order, which the per-point gathers read.
  spring_at_.resize(spring_of_point_.size());
  corner_gradient_.resize(m.has_volume() ? corner_of_point_.size() : 0);
  for_each(m.npoint(), [&](int32_t i) {
    for (int32_t k = spring_start_[i]; k < spring_start_[i + 1]; ++k)
      spring_at_[k] = springs_[spring_of_point_[k] >> 1];
    if (m.has_volume())
      for (int32_t k = corner_start_[i]; k < corner_start_[i + 1]; ++k)
        corner_gradient_[k] = volume_gradient_[corner_of_point_[k] >> 2][corner_of_point_[k] & 3];
  });
  // And into the SIMD passes' slots (the padding's from the zero elements) and tets.
  if (simd_) {
    for_each(streams_.tet_groups, [&](int32_t g) {
      for (int32_t e = kGatherGroup * g; e < kGatherGroup * (g + 1); ++e)
        for (int c = 0; c < 4; ++c)
          for (int a = 0; a < 3; ++a) streams_.tet_gradient[c][a][e] = volume_gradient_[e][c][a];
    });
    for_each(streams_.groups, [&](int32_t g) {
      GatherStreams& s = streams_;
      for (size_t k = size_t{kGatherGroup} * s.spring_row[g]; k < size_t{kGatherGroup} * s.spring_row[g + 1]; ++k) {
        const SpringTangent& tangent = springs_[slot_spring_[k]];
        for (int a = 0; a < 3; ++a) s.u[a][k] = tangent.u[a];
        s.axial[k] = tangent.axial;
        s.transverse[k] = tangent.transverse;
        s.damper[k] = tangent.d;
      }
      for (size_t k = size_t{kGatherGroup} * s.corner_row[g]; k < size_t{kGatherGroup} * s.corner_row[g + 1]; ++k) {
        const Vec3& gradient = volume_gradient_[slot_corner_[k] >> 2][slot_corner_[k] & 3];
        for (int a = 0; a < 3; ++a) s.gradient[a][k] = gradient[a];
      }
    });
  }
  contact_ = contact;
}

ImplicitSystem::ShearRows ImplicitSystem::shear_rows(double alpha, double beta) const {
  if (!model_.has_shear_element()) return {};
  if (!(model_.shear_damping_time > 0)) alpha = 0;
  if (alpha == 0) return {beta != 0 ? &shear_k_ : nullptr, beta};
  if (beta == 0) return {&shear_d_, alpha};
  if (alpha != shear_alpha_ || beta != shear_beta_) {
    shear_ = beta * shear_k_ + alpha * shear_d_;
    shear_alpha_ = alpha;
    shear_beta_ = beta;
  }
  return {&shear_, 1};
}

void ImplicitSystem::apply(double m_coef, double alpha, double beta, const Eigen::VectorXd& p,
                           Eigen::VectorXd& out) const {
  const Model& m = model_;
  const int32_t n = m.npoint();
  out.resize(3 * n);
  const bool volume = m.has_volume() && beta != 0, nodal = volume && m.has_nodal_volume();
  // The SIMD passes take the whole groups of points and of tets, the scalar
  // code the rest (all of them without a target).
  const int32_t point_groups = simd_ ? streams_.groups : 0, tet_groups = simd_ ? streams_.tet_groups : 0;
  // dV_t . p per tet, times beta k_t (per-tet term) or not (nodal).
  const auto tet_dot = [&](int32_t e) {
    const Tet& tet = m.tet_points[e];
    double s = 0;
    for (int i = 0; i < 4; ++i) s += volume_gradient_[e][i].dot(at(p, tet[i]));
    tet_term_[e] = nodal ? s : beta * m.tet_k[e] * s;
  };
  const auto simd_tet_dots = [&](int32_t first, int32_t last) {
    simd_->tet_dots(streams_, p.data(), nodal ? nullptr : m.tet_k.data(), beta, tet_term_.data(), first, last);
  };
  // The nodal term first needs every node's k_a (dV_a . p), dV_a . p =
  // the sum over a's tets of dV_t . p / 4.
  if (nodal) {
    for_each_group(m.ntet(), tet_groups, simd_tet_dots, tet_dot);
    for_each_group(
        n, point_groups,
        [&](int32_t first, int32_t last) {
          simd_->node_sums(streams_, tet_term_.data(), m.point_volume_k.data(), node_term_.data(), first, last);
        },
        [&](int32_t a) {
          double s = 0;
          for (int32_t k = corner_start_[a]; k < corner_start_[a + 1]; ++k) s += tet_term_[corner_of_point_[k] >> 2];
          node_term_[a] = m.point_volume_k[a] * s / 4;
        });
  }
  // Each tet's coefficient c of its corners' terms c dV_t/dx_i: beta k_t
  // dV_t . p, or with the nodal term beta times the mean of its nodes' k_a
  // (dV_a . p).
  if (nodal)
    for_each_group(
        m.ntet(), tet_groups,
        [&](int32_t first, int32_t last) {
          simd_->tet_means(streams_, node_term_.data(), beta, tet_term_.data(), first, last);
        },
        [&](int32_t e) {
          const Tet& tet = m.tet_points[e];
          tet_term_[e] = beta * (node_term_[tet[0]] + node_term_[tet[1]] + node_term_[tet[2]] + node_term_[tet[3]]) / 4;
        });
  else if (volume)
    for_each_group(m.ntet(), tet_groups, simd_tet_dots, tet_dot);
  const ShearRows shear = shear_rows(alpha, beta);
  const auto row_product = [&p](const ShearMatrix& matrix, Eigen::Index r) {
    double sum = 0;
    for (ShearMatrix::InnerIterator it(matrix, r); it; ++it) sum += it.value() * p[it.col()];
    return sum;
  };
  // Each point gathers, in its incidence lists' order: the mass and drag,
  // its springs' terms (a spring's y on end a, -y on end b: evaluated at
  // both ends, as the force pass does, rather than scattered), its tet
  // corners' c dV_t/dx_i, the shear rows.
  const double mass_coef = m_coef + alpha * m.viscous_damping;
  const auto add_shear = [&](int32_t i, double* y) {
    if (shear.matrix)
      for (int a = 0; a < 3; ++a) y[a] += shear.scale * row_product(*shear.matrix, 3 * i + a);
  };
  const auto gather = [&](int32_t i) {
    const Eigen::Map<const Eigen::Vector3d> pi = at(p, i);
    Vec3 y = mass_coef * m.mass[i] * pi;
    for (int32_t k = spring_start_[i]; k < spring_start_[i + 1]; ++k) {
      const SpringTangent& g = spring_at_[k];
      // p_i - p_other: the end's own y, whichever end i is.
      const Vec3 delta = pi - at(p, spring_other_[k]);
      y += (alpha * g.d + beta * g.axial) * g.u.dot(delta) * g.u + beta * g.transverse * delta;
    }
    if (volume)
      for (int32_t k = corner_start_[i]; k < corner_start_[i + 1]; ++k)
        y += tet_term_[corner_of_point_[k] >> 2] * corner_gradient_[k];
    add_shear(i, y.data());
    at(out, i) = y;
  };
  for_each_group(
      n, point_groups,
      [&](int32_t first, int32_t last) {
        const GatherTerms terms{mass_coef, alpha, beta, m.mass.data(), tet_term_.data(), volume};
        simd_->product(streams_, terms, p.data(), out.data(), first, last);
        for (int32_t i = kGatherGroup * first; i < kGatherGroup * last; ++i) add_shear(i, out.data() + 3 * i);
      },
      gather);
  if (beta != 0)
    for (const ContactBlock& c : contact_) {
      Vec3 wp = Vec3::Zero();
      for (int j = 0; j < 3; ++j)
        if (c.point[j] >= 0) wp += c.w[j] * at(p, c.point[j]);
      const Vec3 y = beta * (c.k * wp);
      for (int i = 0; i < 3; ++i)
        if (c.point[i] >= 0) at(out, c.point[i]) += c.w[i] * y;
    }
}

void ImplicitSystem::diagonal_blocks(double m_coef, double alpha, double beta, std::vector<Eigen::Matrix3d>& out) const {
  const Model& m = model_;
  const int32_t n = m.npoint();
  out.resize(n);
  const bool volume = m.has_volume() && beta != 0, nodal = volume && m.has_nodal_volume();
  const ShearRows shear = shear_rows(alpha, beta);
  for_each(n, [&](int32_t i, int slot) {
    Eigen::Matrix3d block = (m_coef + alpha * m.viscous_damping) * m.mass[i] * Eigen::Matrix3d::Identity();
    for (int32_t k = spring_start_[i]; k < spring_start_[i + 1]; ++k) {
      const SpringTangent& g = spring_at_[k];
      block += (alpha * g.d + beta * g.axial) * g.u * g.u.transpose() + beta * g.transverse * Eigen::Matrix3d::Identity();
    }
    if (nodal) {
      // Node a's row of G at i: the sum over the tets of a holding i of
      // dV_t/dx_i / 4, for every node a of i's patch.
      std::vector<Vec3>& row = patch_row_[static_cast<size_t>(slot)];
      const int32_t first = patch_start_[i], size = patch_start_[i + 1] - first;
      row.assign(static_cast<size_t>(size), Vec3::Zero());
      for (int32_t k = corner_start_[i]; k < corner_start_[i + 1]; ++k) {
        const Vec3 g = corner_gradient_[k] / 4;
        for (int j = 0; j < 4; ++j) row[patch_slot_[4 * static_cast<size_t>(k) + j]] += g;
      }
      for (int32_t j = 0; j < size; ++j)
        block += beta * m.point_volume_k[patch_point_[first + j]] * row[j] * row[j].transpose();
    } else if (volume) {
      for (int32_t k = corner_start_[i]; k < corner_start_[i + 1]; ++k) {
        const Vec3& g = corner_gradient_[k];
        block += beta * m.tet_k[corner_of_point_[k] >> 2] * g * g.transpose();
      }
    }
    if (shear.matrix)
      for (int a = 0; a < 3; ++a)
        for (ShearMatrix::InnerIterator it(*shear.matrix, 3 * i + a); it; ++it)
          if (it.col() / 3 == i) block(a, it.col() % 3) += shear.scale * it.value();
    out[i] = block;
  });
  for (const ContactBlock& c : contact_)
    for (int i = 0; i < 3; ++i)
      if (c.point[i] >= 0) out[c.point[i]] += beta * c.w[i] * c.w[i] * c.k;
}

}  // namespace organsim
