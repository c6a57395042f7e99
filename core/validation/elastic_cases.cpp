#include "core/validation/elastic_cases.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <tuple>

#include "core/model/contact_layer.h"
#include "core/model/model.h"
#include "core/model/stiffness.h"
#include "core/physics/force_law.h"
#include "core/util/error.h"
#include "core/validation/run_equilibrium.h"
#include "core/validation/static_solve.h"

namespace organsim {

namespace {

struct Box {
  Vec3 min, max;
  double tol;  // points within this of a face lie on it, m
  Vec3 size() const { return max - min; }
};

Box bounding_box(const Model& m) {
  Box b{Vec3::Constant(1e300), Vec3::Constant(-1e300), 0};
  for (const Vec3& x : m.rest_position) {
    b.min = b.min.cwiseMin(x);
    b.max = b.max.cwiseMax(x);
  }
  b.tol = 1e-6 * b.size().norm();
  return b;
}

// Points of the face where coordinate `axis` is at its min (side < 0) or max.
std::vector<int32_t> face(const Model& m, const Box& b, int axis, int side) {
  std::vector<int32_t> points;
  const double plane = side < 0 ? b.min[axis] : b.max[axis];
  for (int32_t p = 0; p < m.npoint(); ++p)
    if (std::abs(m.rest_position[p][axis] - plane) <= b.tol) points.push_back(p);
  if (points.empty()) throw Error(ErrorKind::Input, "validation mesh: no points on a face of its bounding box");
  return points;
}

int32_t nearest(const Model& m, const std::vector<int32_t>& among, const Vec3& target) {
  return *std::min_element(among.begin(), among.end(), [&](int32_t a, int32_t b) {
    return (m.rest_position[a] - target).squaredNorm() < (m.rest_position[b] - target).squaredNorm();
  });
}

double mean_displacement(const StaticSolution& s, const std::vector<int32_t>& points, int axis) {
  double sum = 0;
  for (int32_t p : points) sum += s.displacement[p][axis];
  return sum / static_cast<double>(points.size());
}

Model free_model(const TetMesh& mesh, const Material& material) {
  return build_model(mesh, material, ModelOptions{}, "validation mesh");
}

void clamp(StaticProblem& problem, const std::vector<int32_t>& points, const Vec3& value) {
  for (int32_t p : points)
    for (int a = 0; a < 3; ++a) problem.prescribed.push_back({p, a, value[a]});
}

}  // namespace

UniaxialResult uniaxial_compression(const TetMesh& block, const Material& material, double strain) {
  const Model m = free_model(block, material);
  const Box b = bounding_box(m);
  const double height = b.size().z();
  const auto bottom = face(m, b, 2, -1), top = face(m, b, 2, +1);
  StaticProblem problem;
  for (int32_t p : bottom) problem.prescribed.push_back({p, 2, 0.0});
  for (int32_t p : top) problem.prescribed.push_back({p, 2, -strain * height});
  // Rigid motions in the bottom plane: pin the middle point in x and y, and a
  // point towards +x in y.
  const Vec3 centre = 0.5 * (b.min + b.max);
  const int32_t pin = nearest(m, bottom, Vec3(centre.x(), centre.y(), b.min.z()));
  const int32_t turn = nearest(m, bottom, Vec3(b.max.x(), centre.y(), b.min.z()));
  problem.prescribed.push_back({pin, 0, 0.0});
  problem.prescribed.push_back({pin, 1, 0.0});
  problem.prescribed.push_back({turn, 1, 0.0});
  const StaticSolution s = solve_static(m, problem);

  double force = 0;  // the platen's push on the top face, N
  for (int32_t p : top) force -= s.reaction[p].z();
  const double area = m.rest_volume() / height;  // mean cross-section, m^2
  UniaxialResult r;
  r.points = m.npoint();
  r.young_modulus = force / area / strain;
  const double ex = (mean_displacement(s, face(m, b, 0, +1), 0) - mean_displacement(s, face(m, b, 0, -1), 0)) /
                    b.size().x();
  const double ey = (mean_displacement(s, face(m, b, 1, +1), 1) - mean_displacement(s, face(m, b, 1, -1), 1)) /
                    b.size().y();
  r.poisson_ratio = 0.5 * (ex + ey) / strain;
  return r;
}

BeamResult cantilever(const TetMesh& beam, const Material& material, BeamEnd end) {
  const Model m = free_model(beam, material);
  const Box box = bounding_box(m);
  const auto root = face(m, box, 0, -1), tip = face(m, box, 0, +1);
  StaticProblem problem;
  clamp(problem, root, Vec3::Zero());
  const double load = 1e-3;  // N for the tip load, m for the guided end: linear, so any small value
  if (end == BeamEnd::TipLoad) {
    problem.load.assign(m.npoint(), Vec3::Zero());
    for (int32_t p : tip) problem.load[p] = Vec3(0, 0, -load / static_cast<double>(tip.size()));
  } else {
    clamp(problem, tip, Vec3(0, 0, -load));
  }
  const StaticSolution s = solve_static(m, problem);

  BeamResult r;
  r.points = m.npoint();
  if (end == BeamEnd::TipLoad) {
    r.stiffness = load / -mean_displacement(s, tip, 2);
  } else {
    double force = 0;
    for (int32_t p : tip) force -= s.reaction[p].z();
    r.stiffness = force / load;
  }
  const EffectiveElasticity e = effective_elasticity(material);
  const double L = box.size().x(), w = box.size().y(), h = box.size().z();
  const double I = w * h * h * h / 12, A = w * h;
  const double nu = e.poisson_ratio;
  const double kappa = 10 * (1 + nu) / (12 + 11 * nu);  // rectangular section (Cowper)
  const double bending = (end == BeamEnd::TipLoad ? 3.0 : 12.0) * e.young_modulus * I / (L * L * L);
  const double shear_compliance = L / (kappa * e.shear_modulus * A);
  r.euler_bernoulli = bending;
  r.timoshenko = 1.0 / (1.0 / bending + shear_compliance);
  return r;
}

namespace {

// A rigid tool as the tool applies it: a capsule, the segment a-b with a
// radius (a == b: a sphere).
struct RigidTool {
  Vec3 a, b;
  double radius = 0;
};

// The surface contact's static response: the penalties' total force on the
// tissue (N), the triangles pushing and the settled displacements (m; empty
// when the tool does not reach the surface).
struct SurfaceContact {
  Vec3 force = Vec3::Zero();
  int32_t touching = 0;
  std::vector<Vec3> displacement;
};

// A capsule lying parallel to a triangle touches it along a chord under its
// axis, and the force law's closest point jumps from one end of that chord
// to the other as the triangle tilts (segment_point_closest_to_triangle): the
// penalty energy is the larger of the two ends', with a kink where they are
// level, and the minimum lies on such kinks. A Gauss-Newton step linearised
// at one end only tilts the triangle onto the other and the line search
// refuses it. So the step's model also holds every other segment-to-edge
// closest pair within 5 % of the triangle's depth, the triangle's penalty
// stiffness shared equally between them (the mean of the kink's sides).
// Only the step's model changes: the energy and the forces are the force
// law's. `spring` is the force law's linearisation at `depth`, `x` the
// triangle's corners at u.
void add_kink_springs(const RigidTool& tool, const Tri& tri, const Vec3 x[3], const std::vector<Vec3>& u,
                      const SurfaceSpring& spring, double depth, std::vector<SurfaceSpring>& springs) {
  const size_t first = springs.size();
  springs.push_back(spring);
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    double s = 0, t = 0;
    force_law::segments_closest(tool.a, tool.b, x[i], x[j], s, t);
    const Vec3 offset = x[i] + t * (x[j] - x[i]) - (tool.a + s * (tool.b - tool.a));
    const double dist = offset.norm(), edge_depth = tool.radius - dist;
    if (!(dist > 0) || !(edge_depth >= 0.95 * depth)) continue;
    SurfaceSpring c = spring;
    c.weights = {0, 0, 0};
    c.weights[i] = 1 - t;
    c.weights[j] = t;
    const auto same_point = [&](const SurfaceSpring& o) {
      for (int k = 0; k < 3; ++k)
        if (std::abs(o.weights[k] - c.weights[k]) > 1e-9) return false;
      return true;
    };
    if (std::any_of(springs.begin() + static_cast<std::ptrdiff_t>(first), springs.end(), same_point)) continue;
    c.direction = offset / dist;
    const Vec3 u_q = c.weights[0] * u[tri[0]] + c.weights[1] * u[tri[1]] + c.weights[2] * u[tri[2]];
    c.target = edge_depth + c.direction.dot(u_q);
    springs.push_back(c);
  }
  const double n = static_cast<double>(springs.size() - first);
  for (size_t k = first; k < springs.size(); ++k) springs[k].k /= n;
}

// The surface contact's static response at one pose: the displacement that
// minimises the elastic energy plus every triangle's penalty
// (force_law::capsule_triangle_penalty's k_t/2 (R - dist)^2 inside the tool),
// by Gauss-Newton with a backtracking line search: each iteration
// linearises the penalty of every triangle inside the tool at its current
// closest point and normal (a SurfaceSpring; for a capsule also
// add_kink_springs), solves, and moves towards that solution by the largest
// of 1, 1/2, 1/4, ... that lowers the energy, until a step changes the push
// (along -z) by less than 1e-6 of itself (1e-4 after 30 iterations); a
// capsule until the supports' reaction settles or no step lowers the energy.
SurfaceContact surface_contact(const Model& m, const StaticSolver& solver, const StaticProblem& supports,
                               const RigidTool& tool, double k_contact) {
  const bool capsule = tool.a != tool.b;
  auto corners = [&](const std::vector<Vec3>& u, int32_t t, Vec3 x[3]) {
    for (int i = 0; i < 3; ++i) x[i] = m.rest_position[m.surface[t][i]] + u[m.surface[t][i]];
  };
  // Triangle t at displacements u: its penalty as a SurfaceSpring (closest
  // point weights, the direction it pushes the tissue, k_t, and a target that
  // makes target - direction . u_q its depth) and its depth (0: outside).
  auto contact = [&](const std::vector<Vec3>& u, int32_t t, SurfaceSpring& s) {
    const Tri& tri = m.surface[t];
    Vec3 x[3];
    corners(u, t, x);
    double share[3];
    for (int i = 0; i < 3; ++i) share[i] = m.tool_scale(tri[i]) / m.surface_count(tri[i]);
    const double k_t = k_contact * force_law::triangle_penalty_scale(share);
    Vec3 f;
    double w[3];
    if (!(k_t > 0) ||
        !force_law::capsule_triangle_penalty(tool.a, tool.b, tool.radius, x[0], x[1], x[2], k_contact, share, f, w))
      return 0.0;
    const double depth = f.norm() / k_t;
    s.points = {tri[0], tri[1], tri[2]};
    s.weights = {w[0], w[1], w[2]};
    s.direction = f / f.norm();
    s.k = k_t;
    const Vec3 u_q = w[0] * u[tri[0]] + w[1] * u[tri[1]] + w[2] * u[tri[2]];
    s.target = depth + s.direction.dot(u_q);
    return depth;
  };
  struct State {
    double energy = 0;
    Vec3 force = Vec3::Zero();
    int32_t touching = 0;
    double push() const { return -force.z(); }
  };
  auto evaluate = [&](const std::vector<Vec3>& u) {
    State st;
    st.energy = solver.elastic_energy(u);
    SurfaceSpring s;
    for (int32_t t = 0; t < m.nsurface(); ++t) {
      const double depth = contact(u, t, s);
      if (!(depth > 0)) continue;
      st.energy += s.k * depth * depth / 2;
      st.force += s.k * depth * s.direction;
      ++st.touching;
    }
    return st;
  };
  auto supports_reaction_z = [&](const std::vector<Vec3>& u) {
    const std::vector<Vec3> elastic = solver.elastic_force(u);
    double sum = 0;
    for (const PrescribedDof& d : supports.prescribed)
      if (d.axis == 2) sum += elastic[d.point].z();
    return sum;
  };
  double last_reaction = 0, before_last_push = 0;
  int quiet = 0;
  std::vector<Vec3> u(m.npoint(), Vec3::Zero());
  State now = evaluate(u);
  if (now.touching == 0) return {};  // the tool does not reach the surface
  for (int iteration = 0;; ++iteration) {
    if (iteration == 100) throw Error(ErrorKind::Numerical, "validation: surface contact did not settle");
    StaticProblem problem = supports;
    SurfaceSpring s;
    for (int32_t t = 0; t < m.nsurface(); ++t) {
      const double depth = contact(u, t, s);
      if (!(depth > 0)) continue;
      if (!capsule) {
        problem.surface_springs.push_back(s);
        continue;
      }
      Vec3 x[3];
      corners(u, t, x);
      add_kink_springs(tool, m.surface[t], x, u, s, depth, problem.surface_springs);
    }
    const StaticSolution sol = solver.solve(problem);
    std::vector<Vec3> next(u.size());
    State tried;
    double step = 1;
    for (;; step /= 2) {
      for (size_t p = 0; p < u.size(); ++p) next[p] = u[p] + step * (sol.displacement[p] - u[p]);
      tried = evaluate(next);
      if (tried.energy <= now.energy || step < 1e-3) break;
    }
    // A capsule's minimum lies on kinks (add_kink_springs) that the model
    // can approach but not resolve: when no step lowers the energy the
    // elastic state has settled, though the force law's penalties, taken
    // on one side of each kink, need not sum to the supports' reaction.
    if (capsule && !(tried.energy < now.energy)) break;
    const double change = std::abs(tried.push() - now.push());
    const double two_back = before_last_push;
    before_last_push = now.push();
    u.swap(next);
    now = tried;
    if (capsule) {
      // Its penalties jump at the kinks, so a capsule's state is judged by
      // the supports' reaction along z (smooth in u): settled when three
      // steps in a row moved it by < 1e-4 of itself.
      const double reaction = supports_reaction_z(u);
      quiet = std::abs(reaction - last_reaction) <= 1e-4 * std::abs(reaction) ? quiet + 1 : 0;
      last_reaction = reaction;
      if (quiet == 3) break;
      continue;
    }
    // Settled: a step of at least a quarter, still touching, that moved the
    // push by < 1e-6 of it, or by < 1e-4 after 30 iterations (where a
    // closest point slides along its triangle, which the linearisation
    // leaves out, the push converges only linearly, and where the touching
    // set alternates the full step is refused every time; 1e-4 is far below
    // the percent-level errors measured). A tiny step changes little without
    // settling anything, and one that left the tool is not a solution.
    // Where a closest point alternates between two features the iterates
    // alternate between two states, each step's change staying near 1e-4
    // while the two-step change falls below 1e-6: that is settled too.
    const double tolerance = iteration < 30 ? 1e-6 : 1e-4;
    const bool alternating = iteration >= 30 && std::abs(now.push() - two_back) <= 1e-6 * std::abs(now.push());
    if (step >= 0.25 && now.touching > 0 && (change <= tolerance * std::abs(now.push()) || alternating)) break;
  }
  return {now.force, now.touching, std::move(u)};
}

// The point contact's static response at one depth: a stiff penalty spring
// on every point inside the sphere; solve; release the points pulled (not
// pushed) by their spring, add those now inside, until the set settles.
// Returns the push along -z (N) and the points touching.
std::pair<double, int32_t> point_indentation(const Model& m, const StaticSolver& solver,
                                             const StaticProblem& supports, const Vec3& centre, double radius,
                                             double k_contact) {
  std::vector<uint8_t> touching(m.npoint(), 0);
  auto penetration = [&](int32_t p, const Vec3& u) { return radius - (m.rest_position[p] + u - centre).norm(); };
  for (int32_t p = 0; p < m.npoint(); ++p) touching[p] = penetration(p, Vec3::Zero()) > 0;
  double force = 0;
  int32_t contacts = 0;
  for (int iteration = 0;; ++iteration) {
    if (iteration == 100) throw Error(ErrorKind::Numerical, "sphere_indentation: contact set did not settle");
    StaticProblem problem = supports;
    for (int32_t p = 0; p < m.npoint(); ++p) {
      if (!touching[p]) continue;
      const Vec3 offset = m.rest_position[p] - centre;
      problem.point_springs.push_back({p, offset.normalized(), k_contact, radius - offset.norm()});
    }
    const StaticSolution s = solver.solve(problem);
    bool changed = false;
    force = 0;
    contacts = 0;
    for (const PointSpring& c : problem.point_springs) {
      const double push = c.k * (c.target - c.direction.dot(s.displacement[c.point]));
      if (push <= 0) {
        touching[c.point] = 0;
        changed = true;
      } else {
        force += push * c.direction.z();
        ++contacts;
      }
    }
    for (int32_t p = 0; p < m.npoint(); ++p)
      if (!touching[p] && penetration(p, s.displacement[p]) > 1e-9 * radius) {
        touching[p] = 1;
        changed = true;
      }
    if (!changed) break;
  }
  return {-force, contacts};
}

}  // namespace

namespace {

// A block with its bottom face clamped, its stiffness factored once for every
// pose of a tool pressed into its top (unless not `factored`: the solves as
// run need none), and the tool's penalty: 1000x the stiffest point, so its
// compliance is 1e-3 of the solid's.
struct ClampedBlock {
  ClampedBlock(const TetMesh& mesh, const Material& material, bool factored = true)
      : model(free_model(mesh, material)), box(bounding_box(model)), bottom(face(model, box, 2, -1)) {
    clamp(supports, bottom, Vec3::Zero());
    const std::vector<double> diagonal = stiffness_diagonal(model);
    k_contact = 1e3 * *std::max_element(diagonal.begin(), diagonal.end());
    if (factored) solver = std::make_unique<StaticSolver>(model, supports.prescribed);
  }
  const Model model;
  const Box box;
  const std::vector<int32_t> bottom;
  StaticProblem supports;
  double k_contact = 0;
  std::unique_ptr<const StaticSolver> solver;  // refers to model
};

// A tool's surface contact in series with the sub-cell layer
// (force_law::HertzLayer::offset_for: a sphere's Hertz layer, a capsule's
// line layer): the tissue sees the tool moved back by delta(F) along the
// push (+z), so the force is the root of F = F_s(d - delta(F)) with F_s the
// layer-less static contact's `push` at a depth. a_h, c, E* and the contact
// length are those of the triangles touching in the last solve, weighed as
// the backends weigh them. The root is bracketed by 0 and F_s(d) (delta >=
// 0) and found by regula falsi (Illinois) to 1e-4 of itself, far below the
// percent-level errors validated. Returns F and the last solve's state.
struct LayeredContact {
  double force = 0;
  SurfaceContact last;
};
LayeredContact layered_contact(const ClampedBlock& b, const ContactLayer& layer, const RigidTool& tool,
                               const std::function<double(const SurfaceContact&)>& push) {
  const Model& m = b.model;
  force_law::HertzLayer sum;
  LayeredContact result;
  auto push_at = [&](double back) {
    const RigidTool moved{tool.a + Vec3(0, 0, back), tool.b + Vec3(0, 0, back), tool.radius};
    result.last = surface_contact(m, *b.solver, b.supports, moved, b.k_contact);
    // Moved back off the surface: no force, and the layer's values stay those of the last contact.
    if (result.last.displacement.empty()) return 0.0;
    sum.clear();
    for (const Tri& t : m.surface) {
      Vec3 x[3];
      double share[3], w[3];
      for (int i = 0; i < 3; ++i) {
        x[i] = m.rest_position[t[i]] + result.last.displacement[t[i]];
        share[i] = m.tool_scale(t[i]) / m.surface_count(t[i]);
      }
      Vec3 f;
      if (!force_law::capsule_triangle_penalty(moved.a, moved.b, moved.radius, x[0], x[1], x[2], b.k_contact, share,
                                               f, w))
        continue;
      const TriangleLayer tl = triangle_layer(layer, t);
      const Vec3 q = w[0] * x[0] + w[1] * x[1] + w[2] * x[2];
      sum.add(f.data(), b.k_contact * force_law::triangle_penalty_scale(share), tl.punch_radius, tl.e_star,
              force_law::segment_axial_position(q, moved.a, moved.b));
    }
    return push(result.last);
  };
  auto offset = [&](double force) { return sum.offset_for(force, tool.radius); };
  // g(F) = F_s(d - delta(F)) - F: positive at 0, at most 0 at F_s(d).
  double lo = 0, hi = push_at(0);
  result.force = hi;
  if (!(hi > 0) || !sum.touching()) return result;
  double g_lo = hi, g_hi = push_at(offset(hi)) - hi;
  for (int iteration = 0; iteration < 40 && hi - lo > 1e-4 * hi; ++iteration) {
    const double F = g_hi < 0 ? hi - g_hi * (hi - lo) / (g_hi - g_lo) : hi;
    const double g = push_at(offset(F)) - F;
    if (g == 0) {
      result.force = F;
      return result;
    }
    if (g > 0) {
      lo = F, g_lo = g, g_hi /= 2;
    } else {
      hi = F, g_hi = g, g_lo /= 2;
    }
  }
  result.force = 0.5 * (lo + hi);
  return result;
}

// The force through the clamped base, K u there (0 without contact).
Vec3 base_reaction(const ClampedBlock& b, const SurfaceContact& c) {
  Vec3 force = Vec3::Zero();
  if (c.displacement.empty()) return force;
  const std::vector<Vec3> elastic = b.solver->elastic_force(c.displacement);
  for (int32_t p : b.bottom) force -= elastic[p];
  return force;
}

// The block as a run's Model: its bottom face (within the box's tolerance) fixed.
Model clamped_model(const TetMesh& block, const Material& material, const Box& box) {
  ModelOptions options;
  FixedSelector bottom;
  bottom.kind = FixedSelector::Kind::Box;
  bottom.min = box.min - Vec3::Constant(box.tol);
  bottom.max = Vec3(box.max.x(), box.max.y(), box.min.z()) + Vec3::Constant(box.tol);
  options.fixed.push_back(bottom);
  return build_model(block, material, options, "validation mesh");
}

// The held sphere's equilibrium in a run (held_tool_equilibrium) on the
// clamped block: the force it pushes the tissue with along -z, and the
// points or triangles touching.
std::pair<double, int32_t> indentation_as_run(const Model& model, const Box& box, const Vec3& centre, double radius,
                                              ToolContact contact, bool hertz_layer, const AsRun& as_run) {
  BackendTool tool;
  tool.present = true;
  tool.radius = radius;
  tool.contact_stiffness = as_run.contact_stiffness;
  tool.contact = contact;
  tool.hertz_layer = hertz_layer && contact == ToolContact::Surface;
  // Lowered from where it clears the top face.
  const Vec3 from(centre.x(), centre.y(), box.max.z() + 1.05 * radius);
  const HeldToolEquilibrium e = held_tool_equilibrium(model, tool, from, centre);
  return {e.reaction.force.z(), e.reaction.contacts};
}

}  // namespace

IndentationResult sphere_indentation(const TetMesh& block, const Material& material, double radius,
                                     const std::vector<double>& depths, ToolContact contact, bool hertz_layer,
                                     std::optional<AsRun> as_run) {
  const bool small_strain = !as_run;
  const ClampedBlock b(block, material, small_strain);
  const ContactLayer layer = hertz_layer && small_strain ? contact_layer(b.model) : ContactLayer{};
  const Model run_model = small_strain ? Model{} : clamped_model(block, material, b.box);
  const EffectiveElasticity e = effective_elasticity(material);
  const double e_star = e.young_modulus / (1 - e.poisson_ratio * e.poisson_ratio);
  IndentationResult r;
  r.points = b.model.npoint();
  for (double depth : depths) {
    const Vec3 centre(0.5 * (b.box.min.x() + b.box.max.x()), 0.5 * (b.box.min.y() + b.box.max.y()),
                      b.box.max.z() + radius - depth);
    double force = 0;
    int32_t touching = 0;
    if (!small_strain) {
      std::tie(force, touching) = indentation_as_run(run_model, b.box, centre, radius, contact, hertz_layer, *as_run);
    } else if (contact == ToolContact::Surface && hertz_layer) {
      const LayeredContact c = layered_contact(b, layer, {centre, centre, radius},
                                               [](const SurfaceContact& s) { return -s.force.z(); });
      force = c.force;
      touching = c.last.touching;
    } else if (contact == ToolContact::Surface) {
      const SurfaceContact c = surface_contact(b.model, *b.solver, b.supports, {centre, centre, radius}, b.k_contact);
      force = -c.force.z();
      touching = c.touching;
    } else {
      std::tie(force, touching) = point_indentation(b.model, *b.solver, b.supports, centre, radius, b.k_contact);
    }
    r.depth.push_back(depth);
    r.force.push_back(force);
    r.hertz.push_back(4.0 / 3.0 * e_star * std::sqrt(radius) * std::pow(depth, 1.5));
    r.contacts.push_back(touching);
  }
  return r;
}

LineLoadResult capsule_line_load(const TetMesh& block, const Material& material, double radius,
                                 const std::vector<double>& depths, bool line_layer) {
  for (double depth : depths)
    if (!(depth > 0 && depth < radius))
      throw Error(ErrorKind::Usage, "capsule_line_load: expected depths in (0, radius), got " + std::to_string(depth) +
                                        " m for radius " + std::to_string(radius) + " m");
  const ClampedBlock b(block, material);
  const ContactLayer layer = line_layer ? contact_layer(b.model) : ContactLayer{};
  // The axis along y over the middle of the top face, reaching 2R beyond
  // each side so the rounded ends lie wholly outside the block.
  const double x = 0.5 * (b.box.min.x() + b.box.max.x());
  LineLoadResult r;
  r.points = b.model.npoint();
  r.capsule_length = b.box.size().y() + 4 * radius;
  for (double depth : depths) {
    const double z = b.box.max.z() + radius - depth;
    const RigidTool capsule{Vec3(x, b.box.min.y() - 2 * radius, z), Vec3(x, b.box.max.y() + 2 * radius, z), radius};
    // The force through the clamped base: at a kink the force law's
    // penalties are one side's (surface_contact), the base carries what
    // holds the settled state.
    const SurfaceContact c =
        line_layer ? layered_contact(b, layer, capsule, [&](const SurfaceContact& s) { return -base_reaction(b, s).z(); })
                         .last
                   : surface_contact(b.model, *b.solver, b.supports, capsule, b.k_contact);
    r.depth.push_back(depth);
    r.force.push_back(base_reaction(b, c));
    r.contact_force.push_back(c.force);
    r.contacts.push_back(c.touching);
  }
  return r;
}

}  // namespace organsim
