#include "core/io/vtk_series.h"

#include <cmath>
#include <cstdio>
#include <ostream>

#include "core/mesh/boundary.h"
#include "core/mesh/vtk_xml.h"
#include "core/sim/reference_forces.h"
#include "core/util/atomic_file.h"
#include "core/util/error.h"

namespace organsim {

namespace {

// Largest |L - r| / r over the six edges of each tet (r from the rest state).
std::vector<double> max_edge_strain(const Model& model, const std::vector<Vec3>& x) {
  std::vector<double> strain(model.tet_points.size());
  for (size_t t = 0; t < model.tet_points.size(); ++t) {
    const Tet& tet = model.tet_points[t];
    double largest = 0;
    for (int a = 0; a < 4; ++a) {
      for (int b = a + 1; b < 4; ++b) {
        const double rest = (model.rest_position[tet[b]] - model.rest_position[tet[a]]).norm();
        const double now = (x[tet[b]] - x[tet[a]]).norm();
        largest = std::max(largest, std::abs(now - rest) / rest);
      }
    }
    strain[t] = largest;
  }
  return strain;
}

// A per-point array in the order of `order` (internal ids, one per file point).
VtkArray point_array(std::string name, const std::vector<int32_t>& order, const std::vector<Vec3>& values) {
  VtkArray a{std::move(name), 3, {}, false};
  a.values.reserve(3 * order.size());
  for (int32_t i : order) a.values.insert(a.values.end(), {values[i].x(), values[i].y(), values[i].z()});
  return a;
}

}  // namespace

VtkSeriesRecorder::VtkSeriesRecorder(const VtkSeriesDef& def, const std::filesystem::path& outdir, double tick,
                                     std::optional<ToolSpec> tool)
    : def_(def), outdir_(outdir), tick_(tick), tool_(std::move(tool)) {
  if (!(def_.rate > 0)) throw Error(ErrorKind::Scenario, "outputs.vtk.rate: expected > 0 states per second");
}

void VtkSeriesRecorder::on_start(const Model& model, Backend& backend) {
  std::error_code ec;
  std::filesystem::create_directories(outdir_ / "vtk", ec);
  if (ec) throw Error(ErrorKind::Output, (outdir_ / "vtk").string() + ": cannot create the folder: " + ec.message());
  backend.positions(positions_);
  const double t = backend.time();
  write_state(model, t, tool_ ? tool_->position_at(t) : Vec3::Zero(), tool_ ? tool_->orientation_at(t) : Quat::Identity(),
              false);
  if (t + tick_ + 1e-9 >= next_due_ / def_.rate) previous_ = positions_;
}

void VtkSeriesRecorder::on_tick(const Model& model, Backend& backend, const TickInfo& info) {
  const double due = next_due_ / def_.rate;
  if (info.t + 1e-9 >= due) {
    backend.positions(positions_);
    write_state(model, info.t, info.tool_center, info.tool_orientation, previous_.size() == positions_.size());
    previous_.clear();
  }
  // The velocity of the next state is its displacement over one tick: keep
  // the positions of the tick before it.
  if (info.t + tick_ + 1e-9 >= next_due_ / def_.rate) backend.positions(previous_);
}

void VtkSeriesRecorder::write_state(const Model& model, double t, const Vec3& tool_center, const Quat& tool_turn,
                                    bool have_previous) {
  const auto n = static_cast<size_t>(model.npoint());
  // Internal id of each file point: the user's numbering, then (surface
  // files) only the points on the boundary.
  std::vector<int32_t> order(model.internal_of_input.begin(), model.internal_of_input.end());
  std::vector<Tri> triangles;
  std::vector<Tet> tets;
  std::vector<int32_t> file_index(n, -1);
  std::vector<int32_t> face_tet;  // each boundary triangle's tet, for its label
  const std::vector<Tri> faces =
      def_.surface_only ? extract_boundary_faces(model.tet_points, &face_tet) : std::vector<Tri>{};
  if (def_.surface_only) {
    std::vector<char> on_surface(n, 0);
    for (const Tri& f : faces) for (int32_t v : f) on_surface[static_cast<size_t>(v)] = 1;
    std::vector<int32_t> kept;
    for (int32_t i : order) if (on_surface[static_cast<size_t>(i)]) kept.push_back(i);
    order = std::move(kept);
  }
  for (size_t k = 0; k < order.size(); ++k) file_index[static_cast<size_t>(order[k])] = static_cast<int32_t>(k);

  std::vector<Vec3> points(order.size()), displacement(n), velocity(n, Vec3::Zero()), force(n, Vec3::Zero());
  for (size_t k = 0; k < order.size(); ++k) points[k] = positions_[static_cast<size_t>(order[k])];
  for (size_t i = 0; i < n; ++i) {
    displacement[i] = positions_[i] - model.rest_position[i];
    if (have_previous) velocity[i] = (positions_[i] - previous_[i]) / tick_;
  }
  VtkAttributes attributes;
  attributes.point_data.push_back(point_array("displacement", order, displacement));
  attributes.point_data.push_back(point_array("velocity", order, velocity));
  VtkArray fixed{"fixed", 1, {}, true};
  for (int32_t i : order) fixed.values.push_back(model.fixed[static_cast<size_t>(i)]);
  attributes.point_data.push_back(std::move(fixed));
  if (tool_ && tool_->mode == ToolMode::Push) {
    // The push contact as the backends apply it (the reference's evaluation
    // of force_law::capsule_triangle_penalty or push_penalty, each point's
    // stiffness share included, and the Hertz layer where the tool has it).
    const ToolPlacement placed = place_tool(tool_->backend_tool(), tool_center, tool_turn);
    if (tool_->contact == ToolContact::Surface) {
      const ContactLayer layer = tool_->hertz_layer ? contact_layer(model) : ContactLayer{};
      reference_surface_forces(model, positions_, placed, tool_->contact_stiffness, force,
                               tool_->hertz_layer ? &layer : nullptr);
    } else {
      reference_push_forces(positions_, placed, tool_->contact_stiffness, force, model.tool_k_scale);
    }
    attributes.point_data.push_back(point_array("tool_force", order, force));
  }

  char name[32];
  if (def_.surface_only) {
    for (const Tri& f : faces) {
      triangles.push_back({file_index[static_cast<size_t>(f[0])], file_index[static_cast<size_t>(f[1])],
                           file_index[static_cast<size_t>(f[2])]});
    }
    VtkArray ids{"point_id", 1, {}, false};
    for (int32_t i : order) ids.values.push_back(model.input_of_internal[static_cast<size_t>(i)]);
    attributes.point_data.push_back(std::move(ids));
    // Each triangle's label is its tet's, so the surface colours by label as
    // the frames do (and a cut face shows what it cut through).
    if (!model.tet_label.empty()) {
      std::vector<int32_t> labels;
      for (int32_t t : face_tet) labels.push_back(model.tet_label[static_cast<size_t>(t)]);
      attributes.cell_data.push_back(label_cell_array(labels));
    }
    std::snprintf(name, sizeof name, "state_%05d.vtp", static_cast<int>(steps_.size()));
  } else {
    VtkArray ratio{"volume_ratio", 1, {}, false};
    for (size_t t_id = 0; t_id < model.tet_points.size(); ++t_id) {
      const Tet& tet = model.tet_points[t_id];
      tets.push_back({file_index[static_cast<size_t>(tet[0])], file_index[static_cast<size_t>(tet[1])],
                      file_index[static_cast<size_t>(tet[2])], file_index[static_cast<size_t>(tet[3])]});
      const double v = signed_volume(positions_[tet[0]], positions_[tet[1]], positions_[tet[2]], positions_[tet[3]]);
      ratio.values.push_back(v / model.tet_rest_volume[t_id]);
    }
    attributes.cell_data.push_back(std::move(ratio));
    attributes.cell_data.push_back({"max_spring_strain", 1, max_edge_strain(model, positions_), false});
    // Each tet's label (a segmentation's), so ParaView can colour or threshold by it.
    if (!model.tet_label.empty()) attributes.cell_data.push_back(label_cell_array(model.tet_label));
    std::snprintf(name, sizeof name, "state_%05d.vtu", static_cast<int>(steps_.size()));
  }

  const std::string file = std::string("vtk/") + name;
  write_file_atomically(outdir_ / file, [&](std::ostream& out) {
    if (def_.surface_only) write_vtp(out, points, triangles, attributes);
    else write_vtu(out, points, tets, attributes);
  });
  steps_.emplace_back(t, file);
  write_file_atomically(outdir_ / "states.pvd", [&](std::ostream& out) { write_pvd(out, steps_); });
  // A state at t satisfies every due time up to t.
  next_due_ = static_cast<int>(std::floor(t * def_.rate + 1e-9)) + 1;
}

}  // namespace organsim
