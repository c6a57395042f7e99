#include "core/validation/elastic_cases.h"

#include <algorithm>
#include <cmath>

#include "core/model/model.h"
#include "core/model/stiffness.h"
#include "core/physics/force_law.h"
#include "core/util/error.h"
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

// The surface contact's static response at one depth: the displacement that
// minimises the elastic energy plus every triangle's penalty
// (force_law::sphere_triangle_penalty's k_t/2 (R - |q - c|)^2 inside the
// sphere), by Gauss-Newton with a backtracking line search: each iteration
// linearises the penalty of every triangle inside the sphere at its current
// closest point and normal (a SurfaceSpring), solves, and moves towards that
// solution by the largest of 1, 1/2, 1/4, ... that lowers the energy, until
// a step changes the push by less than 1e-6 of itself (1e-4 after 30
// iterations). Returns the push along -z (N) and the triangles pushing.
std::pair<double, int32_t> surface_indentation(const Model& m, const StaticSolver& solver,
                                               const StaticProblem& supports, const Vec3& centre, double radius,
                                               double k_contact) {
  // Triangle t at displacements u: its penalty as a SurfaceSpring (closest
  // point weights, normal, k_t, the depth as target at rest) and its depth.
  auto contact = [&](const std::vector<Vec3>& u, int32_t t, SurfaceSpring& s) {
    const Tri& tri = m.surface[t];
    Vec3 x[3];
    double share[3];
    for (int i = 0; i < 3; ++i) {
      x[i] = m.rest_position[tri[i]] + u[tri[i]];
      share[i] = m.tool_scale(tri[i]) / m.surface_count(tri[i]);
    }
    double w[3];
    force_law::triangle_closest_weights(centre, x[0], x[1], x[2], w);
    const Vec3 q = w[0] * x[0] + w[1] * x[1] + w[2] * x[2];
    const double dist = (q - centre).norm();
    s.points = {tri[0], tri[1], tri[2]};
    s.weights = {w[0], w[1], w[2]};
    s.direction = dist > 0 ? Vec3((q - centre) / dist) : Vec3(0, 0, -1);
    s.k = k_contact * force_law::triangle_penalty_scale(share);
    Vec3 rest_q = Vec3::Zero();
    for (int i = 0; i < 3; ++i) rest_q += w[i] * m.rest_position[tri[i]];
    s.target = radius - s.direction.dot(rest_q - centre);
    return radius - dist;
  };
  struct State {
    double energy = 0, push = 0;
    int32_t touching = 0;
  };
  auto evaluate = [&](const std::vector<Vec3>& u) {
    State st;
    st.energy = solver.elastic_energy(u);
    SurfaceSpring s;
    for (int32_t t = 0; t < m.nsurface(); ++t) {
      const double depth = contact(u, t, s);
      if (!(depth > 0)) continue;
      st.energy += s.k * depth * depth / 2;
      st.push -= s.k * depth * s.direction.z();
      ++st.touching;
    }
    return st;
  };
  std::vector<Vec3> u(m.npoint(), Vec3::Zero());
  State now = evaluate(u);
  if (now.touching == 0) return {0.0, 0};  // the sphere does not reach the surface
  for (int iteration = 0;; ++iteration) {
    if (iteration == 100) throw Error(ErrorKind::Numerical, "sphere_indentation: surface contact did not settle");
    StaticProblem problem = supports;
    SurfaceSpring s;
    for (int32_t t = 0; t < m.nsurface(); ++t)
      if (contact(u, t, s) > 0) problem.surface_springs.push_back(s);
    const StaticSolution sol = solver.solve(problem);
    std::vector<Vec3> next(u.size());
    State tried;
    double step = 1;
    for (;; step /= 2) {
      for (size_t p = 0; p < u.size(); ++p) next[p] = u[p] + step * (sol.displacement[p] - u[p]);
      tried = evaluate(next);
      if (tried.energy <= now.energy || step < 1e-3) break;
    }
    const double change = std::abs(tried.push - now.push);
    u.swap(next);
    now = tried;
    // Settled: a step of at least a quarter, still touching, that moved the
    // push by < 1e-6 of it, or by < 1e-4 after 30 iterations (where a
    // closest point slides along its triangle, which the linearisation
    // leaves out, the push converges only linearly, and where the touching
    // set alternates the full step is refused every time; 1e-4 is far below
    // the percent-level errors measured). A tiny step changes little without
    // settling anything, and one that left the sphere is not a solution.
    const double tolerance = iteration < 30 ? 1e-6 : 1e-4;
    if (step >= 0.25 && now.touching > 0 && change <= tolerance * std::abs(now.push)) break;
  }
  return {now.push, now.touching};
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

IndentationResult sphere_indentation(const TetMesh& block, const Material& material, double radius,
                                     const std::vector<double>& depths, ToolContact contact) {
  const Model m = free_model(block, material);
  const Box box = bounding_box(m);
  const auto bottom = face(m, box, 2, -1);
  const std::vector<double> diagonal = stiffness_diagonal(m);
  // Penalty 1000x the stiffest point: its compliance is 1e-3 of the solid's.
  const double k_contact = 1e3 * *std::max_element(diagonal.begin(), diagonal.end());
  const EffectiveElasticity e = effective_elasticity(material);
  const double e_star = e.young_modulus / (1 - e.poisson_ratio * e.poisson_ratio);
  // The bottom clamped at every depth: one factorisation serves them all.
  StaticProblem supports;
  clamp(supports, bottom, Vec3::Zero());
  const StaticSolver solver(m, supports.prescribed);

  IndentationResult r;
  r.points = m.npoint();
  for (double depth : depths) {
    const Vec3 centre(0.5 * (box.min.x() + box.max.x()), 0.5 * (box.min.y() + box.max.y()),
                      box.max.z() + radius - depth);
    const auto [force, touching] = contact == ToolContact::Surface
                                       ? surface_indentation(m, solver, supports, centre, radius, k_contact)
                                       : point_indentation(m, solver, supports, centre, radius, k_contact);
    r.depth.push_back(depth);
    r.force.push_back(force);
    r.hertz.push_back(4.0 / 3.0 * e_star * std::sqrt(radius) * std::pow(depth, 1.5));
    r.contacts.push_back(touching);
  }
  return r;
}

}  // namespace organsim
