#include "core/sim/reference_backend.h"

#include <omp.h>

#include <Eigen/SparseCholesky>
#include <array>
#include <chrono>
#include <cmath>
#include <optional>

#include "core/model/rest_stiffness.h"
#include "core/physics/force_law.h"
#include "core/sim/coarse_space.h"
#include "core/sim/conjugate_gradient.h"
#include "core/sim/implicit_system.h"
#include "core/sim/reference_forces.h"
#include "core/sim/surface_contact.h"
#include "core/util/error.h"
#include "core/util/format.h"

namespace organsim {

const char* preconditioner_name(Preconditioner preconditioner) {
  switch (preconditioner) {
    case Preconditioner::BlockJacobi: return "block_jacobi";
    case Preconditioner::TwoLevel: return "two_level";
    case Preconditioner::RestCholesky: return "rest_cholesky";
  }
  return "";
}

namespace {

// The alternation count's thresholds (count_alternation).
constexpr double kAlternationCosine = -0.9, kAlternationShrink = 0.5, kAlternationFloor = 1e-6;

void flat(const std::vector<Vec3>& v, Eigen::VectorXd& out) {
  out.resize(3 * static_cast<Eigen::Index>(v.size()));
  for (size_t i = 0; i < v.size(); ++i) out.segment<3>(3 * static_cast<Eigen::Index>(i)) = v[i];
}
void unflat(const Eigen::VectorXd& v, std::vector<Vec3>& out) {
  out.resize(static_cast<size_t>(v.size() / 3));
  for (size_t i = 0; i < out.size(); ++i) out[i] = v.segment<3>(3 * static_cast<Eigen::Index>(i));
}

// Everything derived from one Model version (prepare() builds it on the
// change worker's thread; it reads nothing of the run).
struct ReferenceTables {
  const Model* model = nullptr;
  StepPlan plan;
  std::unique_ptr<ImplicitSystem> system;  // implicit integrators only
  std::unique_ptr<CoarseSpace> coarse;     // the two-level preconditioner's
  SurfaceContact<double> surface;
  std::vector<double> tool_scale;
  std::array<std::vector<double>, 3> rest;  // X per axis (the surface pass reads streams)
  Eigen::VectorXd free;                     // 1 per free coordinate, 0 per fixed one
  double alternation_floor = 0;             // m: a step's swing h |dv| below it is noise (1e-6 of the bounding-box diagonal)
};

struct ReferencePrepared final : PreparedModel {
  explicit ReferencePrepared(const Model& next) : PreparedModel(next) {}
  ReferenceTables tables;
};

class ReferenceBackend final : public Backend {
 public:
  ReferenceBackend(const Model& model, const BackendTool& tool, const ImplicitOptions& options, Integrator integrator,
                   int32_t threads)
      : tool_(tool), options_(options), integrator_(integrator), threads_(implicit() ? threads : 1) {
    t_ = pack(model);
    x_ = model.rest_position;
    d_.assign(model.npoint(), Vec3::Zero());
    dv_ = Eigen::VectorXd::Zero(3 * model.npoint());
    stats_.cg_max_iterations = options.cg_max_iterations;
    cg_.threads = threads_;
    // A step's count appended without an allocation for the first 2^16 steps (then by doubling).
    if (implicit()) stats_.cg_iterations.reserve(size_t{1} << 16);
  }

  std::string name() const override { return "cpu"; }
  std::string device() const override {
    if (!implicit()) return "CPU, 1 thread, Verlet (reference, double)";
    return "CPU, " + std::to_string(threads_) + (threads_ > 1 ? " threads, " : " thread, ") +
           (damping_only() ? "implicit damping" : "implicit Euler") + " (" + product_name() + ", double; " +
           preconditioner_name(options_.preconditioner) + "-preconditioned CG)";
  }
  std::string precision() const override { return "double"; }
  const StepPlan& step_plan() const override { return t_.plan; }
  int32_t reaction_latency_ticks() const override { return 0; }
  double time() const override { return time_; }
  const IntegratorStats* integrator_stats() const override { return implicit() ? &stats_ : nullptr; }

  Plan plan() const override {
    Plan plan;
    const Model& m = *t_.model;
    for (Pass pass : t_.plan.passes) plan.passes.push_back({pass_name(pass), pass_detail(pass)});
    if (t_.plan.sutures > 0)
      plan.per_tick.push_back({"suture-rest", std::to_string(t_.plan.sutures) + " sutures' rest lengths from their schedule"});
    const size_t n = static_cast<size_t>(m.npoint());
    if (!implicit()) {
      plan.buffers.push_back({"x, x - x_prev, f", 3 * 3 * n * sizeof(double)});
      plan.dispatches_per_step = 0;
      plan.syncs_per_step = 0;
      return plan;
    }
    plan.buffers.push_back({"x, x - x_prev, dv, CG vectors (r, z, p, q, rhs)", 8 * 3 * n * sizeof(double)});
    plan.buffers.push_back({"spring tangents (u, axial, transverse, d)", static_cast<size_t>(m.nspring()) * 6 * sizeof(double)});
    if (m.has_volume()) plan.buffers.push_back({"tet volume gradients", static_cast<size_t>(m.ntet()) * 12 * sizeof(double)});
    plan.dispatches_per_step = 0;
    plan.syncs_per_step = 0;
    return plan;
  }

  // Where the products' gather runs: "simd (avx2) product" or the scalar "reference".
  std::string product_name() const {
    return options_.simd_product ? "simd (" + options_.simd_product->name + ") product" : "reference";
  }

  std::string pass_detail(Pass pass) const {
    const Model& m = *t_.model;
    switch (pass) {
      case Pass::NodalPressure: return "nodal volumes and pressures (reference)";
      case Pass::ShearSmoothing: return "every point's stress on its node-averaged deformation gradient (reference)";
      case Pass::Springs: return std::to_string(m.nspring()) + " springs and their dampers, scattered (reference)";
      case Pass::Volume: return std::to_string(m.ntet()) + " tets' volume forces, scattered (reference)";
      case Pass::ShearElement: return std::to_string(m.ntet()) + " tets' shear element and its damper (reference)";
      case Pass::Gravity: return "m g on every free point";
      case Pass::SurfaceContact:
        return std::string(shape_name(tool_.shape)) + " against " + std::to_string(m.nsurface()) +
               " surface triangles, as the CPU backend's pass, each touching triangle's normal stiffness recorded";
      case Pass::ToolContact: {
        // With implicit damping the contact, like every elastic force, stays explicit.
        const std::string in_system = !implicit() ? "" : damping_only() ? " (explicit)" : t_.plan.tool == ToolTerm::Pull
                                                                            ? ", k s I each in the system"
                                                                            : ", k n n^T each in the system";
        return (t_.plan.tool == ToolTerm::Pull ? "grasp attachment springs" : "the tool's penalties on the points") +
               in_system;
      }
      case Pass::Linearise:
        if (damping_only())
          return "the dampers' d u u^T, the shear element's damper, drag alpha m I (the elastic and contact forces "
                 "stay explicit: dt below the undamped 2/omega_max)";
        return "the force law's tangent: springs (k - t) u u^T + t I (t = max(T, 0)/L) and d u u^T, the volume "
               "term's k g g^T, the shear element's rest stiffness, drag alpha m I, the contact's blocks";
      case Pass::ConjugateGradient:
        return std::string(damping_only() ? "(M + h D) dv = h f" : "(M + h D + h^2 K) dv = h (f - h K v)") + " by " +
               preconditioner_name(options_.preconditioner) +
               "-preconditioned CG on the free points, matrix-free products (" + product_name() + ") on " +
               std::to_string(threads_) + (threads_ > 1 ? " threads" : " thread") +
               ", warm start from the last dv, relative tolerance " + format_number(options_.cg_tolerance) +
               ", at most " + std::to_string(options_.cg_max_iterations) + " iterations";
      case Pass::VelocityUpdate:
        return "v += dv, x += h v" + (options_.newton_iterations > 1
                                          ? ", then up to " + std::to_string(options_.newton_iterations - 1) +
                                                " Newton iterations with a backtracking line search"
                                          : std::string(" (one linearised solve per step)"));
      case Pass::Integrate:
        return "position Verlet with drag: d' = d + dt^2 f(x, d / dt) / m, x' = x + d' (reference)";
    }
    return "";
  }

  void attach(const Attachment& attachment) override { attachment_ = attachment; }
  void release() override { attachment_ = {}; }
  void positions(std::vector<Vec3>& out) const override { out = x_; }

  void set_state(const std::vector<Vec3>& x, const std::vector<Vec3>& x_prev) override {
    if (x.size() != x_.size() || x_prev.size() != x_.size())
      throw Error(ErrorKind::Input, "set_state: expected " + std::to_string(x_.size()) + " positions");
    x_ = x;
    for (size_t i = 0; i < x.size(); ++i) d_[i] = x[i] - x_prev[i];
    dv_.setZero();
    last_dv_.resize(0);  // a new state: nothing to compare the next step with
  }

  std::unique_ptr<PreparedModel> prepare(const Model& next) const override {
    auto prepared = std::make_unique<ReferencePrepared>(next);
    prepared->tables = pack(next);
    return prepared;
  }

  void adopt(std::unique_ptr<PreparedModel> prepared) override {
    auto* p = dynamic_cast<ReferencePrepared*>(prepared.get());
    if (!p) throw Error(ErrorKind::Backend, "cpu backend (reference): adopt() of a version it did not prepare");
    const Model& next = p->model();
    const size_t old_n = x_.size(), n = static_cast<size_t>(next.npoint());
    if (n < old_n || next.origin.size() != n)
      throw Error(ErrorKind::Backend, "cpu backend (reference): rebuild from a Model with " + std::to_string(n) +
                                          " points after " + std::to_string(old_n) + " (points are append-only)");
    // An appended point starts where its origin is, with its velocity.
    x_.resize(n), d_.resize(n);
    for (size_t i = old_n; i < n; ++i) x_[i] = x_[next.origin[i]], d_[i] = d_[next.origin[i]];
    Eigen::VectorXd dv = Eigen::VectorXd::Zero(3 * static_cast<Eigen::Index>(n));
    dv.head(dv_.size()) = dv_;
    dv_ = dv;
    last_dv_.resize(0);
    std::swap(t_, p->tables);
    t_.surface.take_anchors(p->tables.surface);
    factor_.reset();
  }

  Reaction tick(const TickRequest& request) override {
    const double h = request.dt, tick_start = time_;
    Reaction reaction;
    for (int32_t s = 0; s < request.substeps; ++s) {
      const ToolPlacement placed = request.tool_at(tool_, s);
      const ToolTerm tool = request.tool_active ? t_.plan.tool : ToolTerm::None;
      reaction = implicit() ? step(h, tick_start, tool, placed) : verlet_step(h, tick_start, tool, placed);
      time_ += h;
    }
    return reaction;
  }

 private:
  ReferenceTables pack(const Model& model) const {
    ReferenceTables t;
    t.model = &model;
    t.plan = make_step_plan(model, tool_, integrator_);
    if (implicit()) t.system = std::make_unique<ImplicitSystem>(model, threads_, options_.simd_product);
    if (implicit() && options_.preconditioner == Preconditioner::TwoLevel) t.coarse = std::make_unique<CoarseSpace>(model);
    const int32_t n = model.npoint();
    t.tool_scale.resize(n);
    for (int32_t i = 0; i < n; ++i) t.tool_scale[i] = model.tool_scale(i);
    for (int a = 0; a < 3; ++a) {
      t.rest[a].resize(n);
      for (int32_t i = 0; i < n; ++i) t.rest[a][i] = model.rest_position[i][a];
    }
    Vec3 lo = model.rest_position.empty() ? Vec3::Zero() : model.rest_position[0], hi = lo;
    for (const Vec3& p : model.rest_position) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    t.alternation_floor = kAlternationFloor * (hi - lo).norm();
    t.free = Eigen::VectorXd::Ones(3 * n);
    for (int32_t i = 0; i < n; ++i)
      if (model.fixed[i]) t.free.segment<3>(3 * i).setZero();
    if (t.plan.tool == ToolTerm::Surface) {
      t.surface.pack(model, t.tool_scale, static_cast<size_t>(n), tool_.hertz_layer);
      t.surface.record_touches(implicit());
    }
    return t;
  }

  // f(x, v) on every point: the internal forces, the drag -alpha m v and the
  // tool's; `contact` (the implicit integrators'; null under Verlet) gets
  // the tool's stiffness blocks; returns the reaction.
  Reaction forces(const std::vector<Vec3>& x, const std::vector<Vec3>& v, double t, ToolTerm tool,
                  const ToolPlacement& placed, std::vector<Vec3>& f, std::vector<ContactBlock>* contact) {
    const Model& m = *t_.model;
    reference_internal_forces(m, x, v, f, t);
    for (int32_t i = 0; i < m.npoint(); ++i) f[i] -= m.viscous_damping * m.mass[i] * v[i];
    if (contact) contact->clear();
    const double k = tool_.contact_stiffness;
    const auto point_block = [&](int32_t p, const Eigen::Matrix3d& block) {
      ContactBlock c;
      c.point[0] = p;
      c.w[0] = 1;
      c.k = block;
      contact->push_back(c);
    };
    switch (tool) {
      case ToolTerm::None: return {};
      case ToolTerm::Push: {
        for (int32_t i = 0; contact && i < m.npoint(); ++i) {
          const Vec3 offset = x[i] - force_law::segment_closest_point(x[i], placed.a, placed.b);
          const double dist = offset.norm();
          if (!(dist < placed.radius)) continue;
          const Vec3 n = dist > 0 ? Vec3(offset / dist) : Vec3(0, 0, 1);
          point_block(i, force_law::penalty_normal_stiffness(k * t_.tool_scale[i], n));
        }
        return reference_push_forces(x, placed, k, f, t_.tool_scale);
      }
      case ToolTerm::Pull:
        if (contact)
          for (int32_t p : attachment_.points) point_block(p, k * t_.tool_scale[p] * Eigen::Matrix3d::Identity());
        return reference_pull_forces(x, attachment_, placed.origin, k, f, t_.tool_scale);
      case ToolTerm::Surface: break;
    }
    // The surface pass on the CPU backend's streams: X per axis and u = x - X.
    for (int a = 0; a < 3; ++a) {
      u_[a].resize(x.size());
      for (size_t i = 0; i < x.size(); ++i) u_[a][i] = x[i][a] - t_.rest[a][i];
    }
    t_.surface.evaluate({t_.rest[0].data(), t_.rest[1].data(), t_.rest[2].data()},
                        {u_[0].data(), u_[1].data(), u_[2].data()}, placed, k, tool_.friction, 1);
    Reaction reaction;
    const int32_t* slot = t_.surface.slot();
    for (int32_t p = 0; p < m.npoint(); ++p) {
      if (slot[p] < 0) continue;
      const Vec3 fp(t_.surface.force()[3 * slot[p]], t_.surface.force()[3 * slot[p] + 1],
                    t_.surface.force()[3 * slot[p] + 2]);
      f[p] += fp;
      reaction.force -= fp;
      reaction.torque += (x[p] - placed.origin).cross(-fp);
      ++reaction.contacts;
    }
    reaction.grip = t_.surface.grip();
    if (!contact) return reaction;
    for (const auto& touch : t_.surface.touches()) {
      ContactBlock c;
      for (int j = 0; j < 3; ++j) c.point[j] = touch.point[j], c.w[j] = touch.w[j];
      c.k = force_law::penalty_normal_stiffness(touch.k, touch.n);
      contact->push_back(c);
    }
    for (const auto& stick : t_.surface.sticks())
      point_block(stick.point, stick.k * (Eigen::Matrix3d::Identity() - stick.n * stick.n.transpose()));
    return reaction;
  }

  // One position Verlet step of h from the state (x_, d_ = h v), as the
  // CPU backend's kernel steps it: a fixed point's increment (nonzero only
  // when set_state gave it one) moves its dampers for this step, then is 0.
  Reaction verlet_step(double h, double t, ToolTerm tool, const ToolPlacement& placed) {
    const Model& m = *t_.model;
    const int32_t n = m.npoint();
    v_.resize(n);
    for (int32_t i = 0; i < n; ++i) v_[i] = d_[i] / h;
    const Reaction reaction = forces(x_, v_, t, tool, placed, f_, nullptr);
    for (int32_t i = 0; i < n; ++i) {
      if (m.fixed[i]) {
        d_[i].setZero();
        continue;
      }
      d_[i] += h * h * m.inv_mass[i] * f_[i];
      x_[i] += d_[i];
    }
    return reaction;
  }

  // One backward Euler step of h from the state (x_, d_ = h v). Its
  // vectors are members: once sized, a step allocates nothing, Newton
  // iterations included (ImplicitEuler.AStepAllocatesNothingOnceSizedWithOrWithoutNewtonIterations).
  Reaction step(double h, double t, ToolTerm tool, const ToolPlacement& placed) {
    const Model& m = *t_.model;
    const int32_t n = m.npoint();
    ImplicitSystem& system = *t_.system;
    const Eigen::VectorXd& free = t_.free;
    v_.resize(n);
    for (int32_t i = 0; i < n; ++i) v_[i] = m.fixed[i] ? Vec3::Zero() : Vec3(d_[i] / h);
    const Reaction reaction = forces(x_, v_, t, tool, placed, f_, &contact_);
    system.linearise(x_, v_, t, contact_);
    flat(v_, v0_);
    // Implicit damping: no K in the system, none in the right-hand side.
    const double beta = damping_only() ? 0 : h * h;
    kv_.setZero(v0_.size());
    if (beta != 0) system.apply(0, 0, 1, v0_, kv_);
    flat(f_, rhs_);
    rhs_ = h * rhs_ - beta * kv_;
    int32_t iterations = 0;
    double residual = 0;
    bool converged = true;
    const LinearOperator precondition = preconditioner(h, beta);
    // One reference captured: std::function keeps it without an allocation.
    const struct {
      const ImplicitSystem* system;
      double h, beta;
    } op{&system, h, beta};
    const LinearOperator product = [&op](const Eigen::VectorXd& p, Eigen::VectorXd& y) {
      op.system->apply(1, op.h, op.beta, p, y);
    };
    const auto solve = [&](const Eigen::VectorXd& b, Eigen::VectorXd& x) {
      const auto start = std::chrono::steady_clock::now();
      const CgResult r =
          conjugate_gradient(product, precondition, b, free, options_.cg_tolerance, options_.cg_max_iterations, x, cg_);
      stats_.cg_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      iterations += r.iterations;
      residual = std::max(residual, r.residual);
      converged = converged && r.converged;
    };
    solve(rhs_, dv_);
    v1_ = v0_ + dv_;
    if (options_.newton_iterations > 1) newton(h, t, tool, placed, v0_, v1_, solve);
    for (int32_t i = 0; i < n; ++i) {
      if (m.fixed[i]) continue;
      d_[i] = h * Vec3(v1_.segment<3>(3 * static_cast<Eigen::Index>(i)));
      x_[i] += d_[i];
    }
    stats_.cg_iterations.push_back(iterations);
    stats_.max_residual = std::max(stats_.max_residual, residual);
    if (!converged) ++stats_.unconverged_steps;
    count_alternation(h);
    return reaction;
  }

  // This step's velocity change against the last one's: a swing back of
  // about its size (cosine below kAlternationCosine, at least
  // kAlternationShrink of it) that moves a point more than the floor is
  // counted (IntegratorStats::alternating_steps).
  void count_alternation(double h) {
    step_dv_ = v1_ - v0_;
    if (last_dv_.size() == step_dv_.size()) {
      const double now = step_dv_.norm(), before = last_dv_.norm();
      const bool swung_back = now > 0 && before > 0 && step_dv_.dot(last_dv_) < kAlternationCosine * now * before;
      if (swung_back && now >= kAlternationShrink * before && h * step_dv_.lpNorm<Eigen::Infinity>() > t_.alternation_floor)
        ++stats_.alternating_steps;
    }
    std::swap(last_dv_, step_dv_);
  }

  // Newton iterations 2.. on g(v) = M (v - v0) - h f(x0 + h v, v), each
  // solving (M + h D + h^2 K) dv = -g at the new state, its step halved
  // (at most 4 times) while |g| does not fall. Its vectors are members, so
  // that once sized it allocates nothing either.
  template <class Solve>
  void newton(double h, double t, ToolTerm tool, const ToolPlacement& placed, const Eigen::VectorXd& v0,
              Eigen::VectorXd& v, const Solve& solve) {
    const Model& m = *t_.model;
    NewtonVectors& n = newton_;
    n.mass.resize(v.size());
    for (int32_t i = 0; i < m.npoint(); ++i) n.mass.segment<3>(3 * i).setConstant(m.mass[i]);
    // g at velocities `vel` into `g`, the system linearised there when asked.
    const auto residual = [&](const Eigen::VectorXd& vel, bool linearise, Eigen::VectorXd& g) {
      unflat(vel, n.v);
      n.x = x_;
      for (int32_t i = 0; i < m.npoint(); ++i)
        if (!m.fixed[i]) n.x[i] += h * n.v[i];
      forces(n.x, n.v, t, tool, placed, n.f, &n.contact);
      if (linearise) t_.system->linearise(n.x, n.v, t, n.contact);
      flat(n.f, n.flat_f);
      g = (n.mass.cwiseProduct(vel - v0) - h * n.flat_f).cwiseProduct(t_.free);
    };
    residual(v, true, n.g);
    stats_.last_newton_residuals.clear();
    stats_.last_newton_residuals.push_back(n.g.norm());
    for (int32_t k = 1; k < options_.newton_iterations; ++k) {
      n.step.setZero(v.size());
      n.minus_g = -n.g;
      solve(n.minus_g, n.step);
      double alpha = 1;
      n.trial = v + n.step;
      residual(n.trial, false, n.g_trial);
      for (int halvings = 0; halvings < 4 && n.g_trial.norm() > n.g.norm(); ++halvings) {
        alpha /= 2;
        n.trial = v + alpha * n.step;
        residual(n.trial, false, n.g_trial);
      }
      v = n.trial;
      stats_.last_newton_residuals.push_back(n.g_trial.norm());
      if (k + 1 < options_.newton_iterations) residual(v, true, n.g);
    }
  }

  // z = P r: block Jacobi at the current linearisation (with the coarse
  // space's correction for two_level), or the rest system's factor.
  // body(i) for every point's diagonal block, on threads_ threads (no
  // OpenMP region on one: libgomp allocates a team for every region).
  template <class Body>
  void for_each_point(const Body& body) const {
    const int32_t n = static_cast<int32_t>(blocks_.size());
    if (threads_ > 1 && !omp_in_parallel()) {
#pragma omp parallel for schedule(static) num_threads(threads_)
      for (int32_t i = 0; i < n; ++i) body(i);
    } else {
      for (int32_t i = 0; i < n; ++i) body(i);
    }
  }

  LinearOperator preconditioner(double h, double beta) {
    if (options_.preconditioner == Preconditioner::RestCholesky) {
      if (!factor_ || factor_h_ != h) factor_rest_system(h, beta);
      return [this](const Eigen::VectorXd& r, Eigen::VectorXd& z) {
        rf_.resize(static_cast<Eigen::Index>(free_index_.size()));
        for (size_t i = 0; i < free_index_.size(); ++i) rf_[static_cast<Eigen::Index>(i)] = r[free_index_[i]];
        // factor_->solve(rf_) written out as Eigen's own steps, allocating
        // nothing: solve() evaluates into a temporary, and vectorD()
        // returns a copy (its inverse is kept from the factoring instead).
        yf_.noalias() = factor_->permutationP() * rf_;
        factor_->matrixL().solveInPlace(yf_);
        yf_.array() *= factor_inverse_d_.array();
        factor_->matrixU().solveInPlace(yf_);
        zf_.noalias() = factor_->permutationPinv() * yf_;
        z.setZero(r.size());
        for (size_t i = 0; i < free_index_.size(); ++i) z[free_index_[i]] = zf_[static_cast<Eigen::Index>(i)];
      };
    }
    t_.system->diagonal_blocks(1, h, beta, blocks_);
    // Each point's block on its own: threads change nothing.
    for_each_point([this](int32_t i) { blocks_[i] = blocks_[i].inverse().eval(); });
    CoarseSpace* coarse = t_.coarse.get();
    if (coarse) coarse->factor(h, beta);
    return [this, coarse](const Eigen::VectorXd& r, Eigen::VectorXd& z) {
      z.resize(r.size());
      for_each_point([&](int32_t i) {
        z.segment<3>(3 * static_cast<Eigen::Index>(i)) = blocks_[i] * r.segment<3>(3 * static_cast<Eigen::Index>(i));
      });
      if (coarse) coarse->add_correction(r, z);
    };
  }

  // M + h D_rest + h^2 K_rest on the free coordinates, factored (the
  // contact's blocks left out: they come and go with the tool).
  void factor_rest_system(double h, double beta) {
    const Model& m = *t_.model;
    const Triplets t = rest_system(m, h, beta);
    std::vector<int32_t> index(3 * m.npoint(), -1);
    free_index_.clear();
    for (int32_t i = 0; i < 3 * m.npoint(); ++i)
      if (t_.free[i] != 0) index[i] = static_cast<int32_t>(free_index_.size()), free_index_.push_back(i);
    Triplets ff;
    ff.reserve(t.size());
    for (const auto& e : t)
      if (index[e.row()] >= 0 && index[e.col()] >= 0) ff.emplace_back(index[e.row()], index[e.col()], e.value());
    const auto nf = static_cast<Eigen::Index>(free_index_.size());
    Eigen::SparseMatrix<double> a(nf, nf);
    a.setFromTriplets(ff.begin(), ff.end());
    factor_ = std::make_unique<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>>(a);
    if (factor_->info() != Eigen::Success)
      throw Error(ErrorKind::Numerical, "implicit Euler: the rest system M + h D + h^2 K could not be factored");
    factor_inverse_d_ = factor_->vectorD().cwiseInverse();
    factor_h_ = h;
  }

  bool implicit() const { return solves_implicitly(integrator_); }
  bool damping_only() const { return integrator_ == Integrator::ImplicitDamping; }

  BackendTool tool_;
  ImplicitOptions options_;
  Integrator integrator_;
  int32_t threads_;  // the implicit solve's
  ReferenceTables t_;
  std::vector<Vec3> x_, d_;  // positions and the last step's increment h v
  Eigen::VectorXd dv_;       // the last solve's dv: the next one's warm start
  Attachment attachment_;
  double time_ = 0;
  IntegratorStats stats_;
  std::array<std::vector<double>, 3> u_;  // the surface pass's displacement streams
  std::vector<Eigen::Matrix3d> blocks_;    // block Jacobi's inverses
  std::unique_ptr<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>> factor_;
  Eigen::VectorXd factor_inverse_d_;  // 1 / the factor's D
  double factor_h_ = 0;
  std::vector<int32_t> free_index_;  // the factor's coordinates
  std::vector<Vec3> v_, f_;  // the step's velocities (implicit: at its start) and forces
  // The implicit step's: contact blocks, v at the start and the end, K v,
  // the right-hand side, the CG's vectors, the factor's right-hand side,
  // its permuted solve and the solution.
  std::vector<ContactBlock> contact_;
  Eigen::VectorXd v0_, v1_, kv_, rhs_, rf_, yf_, zf_;
  Eigen::VectorXd step_dv_, last_dv_;  // this step's and the last one's v1 - v0 (empty: none to compare)
  CgWorkspace cg_;
  // Newton iterations': the state at the trial velocities, its forces and
  // contact, the lumped masses per coordinate, the residuals and the step.
  struct NewtonVectors {
    std::vector<Vec3> x, v, f;
    std::vector<ContactBlock> contact;
    Eigen::VectorXd mass, flat_f, g, g_trial, minus_g, step, trial;
  } newton_;
};

}  // namespace

std::unique_ptr<Backend> make_reference_backend(const Model& model, const BackendTool& tool, Integrator integrator,
                                                const ImplicitOptions& options, int32_t threads) {
  if (threads < 1)
    throw Error(ErrorKind::Usage, "reference backend: threads must be >= 1 (got " + std::to_string(threads) + ")");
  if (options.newton_iterations > 1 && integrator == Integrator::ImplicitDamping)
    throw Error(ErrorKind::Usage, "implicit damping: newton_iterations must be 1 (its system is linear in v and "
                                  "solved exactly)");
  if (options.newton_iterations < 1)
    throw Error(ErrorKind::Usage, "implicit Euler: newton_iterations must be >= 1 (got " +
                                      std::to_string(options.newton_iterations) + ")");
  if (!(options.cg_tolerance >= 0))
    throw Error(ErrorKind::Usage, "implicit Euler: cg_tolerance must be >= 0");
  if (options.cg_max_iterations < 1)
    throw Error(ErrorKind::Usage, "implicit Euler: cg_max_iterations must be >= 1 (got " +
                                      std::to_string(options.cg_max_iterations) + ")");
  if (options.newton_iterations > 1 && tool.present && tool.friction.on())
    throw Error(ErrorKind::Usage,
                "implicit Euler: newton_iterations > 1 with a tool that has friction is not supported (the "
                "friction anchors advance at every evaluation of the contact); use newton_iterations 1");
  return std::make_unique<ReferenceBackend>(model, tool, options, integrator, threads);
}

}  // namespace organsim
