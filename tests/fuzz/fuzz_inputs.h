#pragma once
// What each kind of harness does with one input, read as the file `source`:
// the harnesses (fuzz_<kind>.cpp) call these, and so does the seed test
// (tests/meshing/fuzz_seeds_test.cpp), which runs every seed of the corpus
// through them. Each either accepts the input (and then checks what the next
// stage relies on, stopping with fuzz::broken when that does not hold, and
// returns what it read) or throws the organsim::Error that refuses it.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "core/fit/measured_curve.h"
#include "core/live/client_command.h"
#include "core/live/client_frame.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_io_detail.h"
#include "core/mesh/mesh_stats.h"
#include "core/mesh/tet_mesh.h"
#include "core/run/run.h"
#include "core/scenario/scenario.h"
#include "core/stability/critical_step.h"
#include "core/stability/study_files.h"
#include "core/sweep/case_names.h"
#include "core/sweep/case_status.h"
#include "core/sweep/sweep_plan.h"
#include "core/sweep/sweep_results.h"
#include "core/sweep/sweep_spec.h"
#include "igtl/igtl_stream.h"
#include "meshing/label_image.h"
#include "meshing/surface_check.h"
#include "tests/fuzz/fuzz_check.h"

namespace organsim::fuzz {

// kind surface: parse_surface; an accepted surface is valid and survives an
// OFF round trip unchanged (the writers print the shortest exact text).
inline TriangleMesh surface_input(std::string_view text, const std::string& source) {
  TriangleMesh mesh = parse_surface(text, source);
  require_valid_surface(mesh);
  std::ostringstream off;
  mesh_io::write_off(off, mesh);
  const TriangleMesh again = parse_surface(off.str(), "again.off");
  require(again.points == mesh.points && again.faces == mesh.faces, "OFF round trip changed the surface");
  return mesh;
}

inline void require_tet_round_trip(const TetMesh& mesh, const char* name,
                                   void (*write)(std::ostream&, const TetMesh&)) {
  std::ostringstream out;
  write(out, mesh);
  const TetMesh again = parse_tet_mesh(out.str(), name);
  require(again.points == mesh.points && again.tets == mesh.tets,
          std::string("round trip through ") + name + " changed the mesh");
}

// kind tet: parse_tet_mesh (read, orient, validate); an accepted mesh is
// valid and survives medit and VTK round trips unchanged.
inline TetMesh tet_input(std::string_view text, const std::string& source) {
  TetMesh mesh = parse_tet_mesh(text, source);
  require_valid_tet_mesh(mesh);
  require_tet_round_trip(mesh, "again.mesh", mesh_io::write_medit);
  require_tet_round_trip(mesh, "again.vtk", mesh_io::write_vtk);
  return mesh;
}

// kind scenario, first stage: the JSON parse. An accepted scenario has a
// positive time, at least one tick and a usable mesh.scale.
inline Scenario scenario_input(std::string_view text, const std::string& source) {
  Scenario s = parse_scenario_text(text, "/fuzz", source);
  require(s.time.dt > 0 && s.time.substeps > 0 && s.time.duration > 0, "scenario accepted a non-positive time");
  require(s.time.ticks() >= 1, "scenario accepted a run of no ticks");
  require(std::isfinite(s.mesh.scale) && s.mesh.scale > 0, "scenario accepted a bad mesh.scale");
  if (s.tool) {
    for (const Keyframe& k : s.tool->spec.keyframes)
      require(k.orientation.coeffs().allFinite() && std::abs(k.orientation.norm() - 1) < 1e-12,
              "scenario accepted an orientation that is not a unit quaternion");
    if (s.tool->spec.shape == ToolShape::Capsule)
      require(s.tool->spec.end_a != s.tool->spec.end_b, "scenario accepted a capsule of zero length");
  }
  return s;
}

// kind scenario, second stage: what `organsim run` does before the first
// step that depends on the scenario alone (the Model on a small box scaled
// by mesh.scale and labelled for per-label materials, the critical time step
// and its check, the backend's tool).
// The mesh file itself is not read: the mesh readers have their own
// harnesses. Its errors name the JSON path or the mesh (cmd_run adds the file).
inline void scenario_model(const Scenario& s) {
  TetMesh mesh = make_box_tet_mesh({0, 0, 0}, {0.1, 0.1, 0.1}, 2, 2, 2);
  for (Vec3& p : mesh.points) p *= s.mesh.scale;
  // Per-label materials need a labelled mesh: the box's tets take the labels
  // the materials name, in turn.
  std::vector<int32_t> labels;
  for (const LabelMaterial& m : s.materials) labels.insert(labels.end(), m.labels.begin(), m.labels.end());
  if (!labels.empty())
    for (size_t t = 0; t < mesh.tets.size(); ++t) mesh.labels.push_back(labels[t % labels.size()]);
  // The scenario's box, plane and sphere selectors are written for its own
  // mesh, not this stand-in: those that match none of the box's points are
  // left out (build_model refuses them, as it should for a real mesh).
  ModelOptions options = model_options(s);
  std::erase_if(options.fixed, [&](const FixedSelector& f) {
    if (f.kind == FixedSelector::Kind::Indices || f.kind == FixedSelector::Kind::Label) return false;
    return std::none_of(mesh.points.begin(), mesh.points.end(), [&](const Vec3& x) { return selector_matches(f, x); });
  });
  const Model model = build_model(mesh, s.material, options, "box.mesh");
  const ToolSpec* tool = s.tool ? &s.tool->spec : nullptr;
  const StabilityReport report = estimate_critical_step(model, critical_step_options(model, tool));
  check_time_step(report, s.time.dt, s.time.substeps, /*allow_unstable=*/false);
  (void)backend_tool(s);
}

// kind surface_check: the checks that guard CGAL Mesh_3 (meshing/
// surface_check.h); a surface that passes is valid, closed (at least 4
// faces) and encloses a positive volume.
inline TriangleMesh surface_check_input(std::string_view text, const std::string& source) {
  const TriangleMesh surface = parse_surface(text, source);
  std::vector<std::string> notes;
  const TriangleMesh checked = check_surface(surface, source, notes);
  require_valid_surface(checked);
  require(checked.faces.size() >= 4, "a closed surface with fewer than 4 faces passed");
  require(surface_volume(checked) > 0, "a surface enclosing no positive volume passed");
  return checked;
}

// kind sweep: parse the sweep file, expand it and build every case's
// scenario (what `organsim sweep` does before it runs anything). The base
// scenario is always scenarios/stress/gentle_push.json (a fuzzed "scenario"
// path could name /dev/zero). An accepted sweep has cases, each with a
// valid name and a scenario.
inline Sweep sweep_input(std::string_view text, const std::string& source) {
  nlohmann::ordered_json j;
  try {
    j = nlohmann::ordered_json::parse(text);
  } catch (const nlohmann::json::exception&) {
    parse_sweep_text(std::string(text), source);  // must refuse it, naming the file
    broken("invalid JSON accepted");
  }
  if (j.is_object()) j["scenario"] = ORGANSIM_SOURCE_DIR "/scenarios/stress/gentle_push.json";
  Sweep sweep = parse_sweep(j, source);
  require(!sweep.cases.empty(), "sweep accepted without cases");
  for (const SweepCase& c : sweep.cases) {
    require(case_name_problem(c.name).empty(), "sweep accepted a bad case name: " + c.name);
    require(!c.scenario_text.empty(), "sweep case without a scenario");
  }
  return sweep;
}

// kind study: the files a sharded `organsim study` shares (study_plan.json,
// study_reference.json, study_runs/<k>.json), each read by the parser its
// "format" names (any other: the plan's, which refuses it). An accepted file
// survives a round trip unchanged: the shards and --collect read back exactly
// what was written. Returns the configurations, samples or 1 (a run).
inline size_t study_input(std::string_view text, const std::string& source) {
  const nlohmann::json j = parse_study_json(std::string(text), source);
  const std::string format = j.is_object() && j.contains("format") && j["format"].is_string() ? j["format"].get<std::string>() : "";
  if (format == "organsim study reference 1") {
    const Trajectory t = parse_trajectory(j, source);
    const Trajectory again = parse_trajectory(trajectory_json(t), "again.json");
    require(again.ticks == t.ticks && again.positions == t.positions && again.force == t.force &&
                again.latency_ticks == t.latency_ticks,
            "reference round trip changed the trajectory");
    return t.ticks.size();
  }
  if (format == "organsim study run 1") {
    const StudyOutcome o = parse_outcome_record(j, source);
    require(outcome_record_json(parse_outcome_record(outcome_record_json(o), "again.json")) == outcome_record_json(o),
            "run round trip changed the outcome");
    return 1;
  }
  const StudyPlan plan = parse_study_plan(j, source);
  require(plan.dt_crit > 0, "plan accepted without a positive dt_crit");
  require(plan_json(parse_study_plan(plan_json(plan), "again.json")) == plan_json(plan),
          "plan round trip changed the plan");
  return plan.configurations.size();
}

// An upper bound on the cases a sweep file expands to (the sweep harness
// skips inputs above 256 to keep each execution short; the limit itself is
// tested in tests/core).
inline size_t sweep_case_bound(std::string_view text) {
  const nlohmann::ordered_json j = nlohmann::ordered_json::parse(text, nullptr, false);
  if (!j.is_object()) return 1;
  auto length = [](const nlohmann::ordered_json& v) -> size_t { return v.is_array() ? std::max<size_t>(1, v.size()) : 1; };
  size_t n = j.contains("cases") ? length(j["cases"]) : 1;
  for (const char* section : {"grid", "zip"}) {
    if (!j.contains(section) || !j[section].is_object()) continue;
    for (const auto& item : j[section].items()) {
      n *= length(item.value());
      if (n > 256) return n;
      if (section[0] == 'z') break;  // zip: one axis
    }
  }
  return n;
}

// kind label_image: the labelled-image readers (.nii .nii.gz .nrrd .inr by
// the name's extension). Their libraries read files by name, so the bytes
// are written to a file named `source` in a folder of this process first;
// errors name that path. An accepted image is consistent.
inline LabelImage label_image_input(std::string_view bytes, const std::string& source,
                                    std::filesystem::path* written = nullptr) {
  // ORGANSIM_FUZZ_IMAGE_DIR (scripts/fuzz.sh: one per harness) keeps the
  // path, and so the error messages the fuzzer compares, the same from run
  // to run; else a folder of this process.
  static const std::filesystem::path dir = [] {
    const char* fixed = std::getenv("ORGANSIM_FUZZ_IMAGE_DIR");
    const auto d = fixed != nullptr && *fixed != 0
                       ? std::filesystem::path(fixed)
                       : std::filesystem::temp_directory_path() / ("organsim_fuzz_image_" + std::to_string(getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  const std::filesystem::path path = dir / source;
  if (written) *written = path;
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  LabelImage image = read_label_image(path);
  require(image.voxel_count() > 0 && image.voxel_count() <= kMaxImageVoxels, "image accepted with a bad voxel count");
  require(static_cast<int64_t>(image.labels.size()) == image.voxel_count(), "labels do not match the size");
  for (int32_t l : image.labels) require(l >= 0, "image accepted with a negative label");
  require(image.axes.allFinite() && image.origin.allFinite() && image.axes.determinant() != 0,
          "image accepted with a degenerate placement");
  return image;
}

// kind measured_curve: the CSV force curve of `organsim fit --measured`
// (parse_measured_curve). An accepted curve has finite, strictly increasing
// abscissae (at least 2), known distinct force columns and one finite value
// per column and sample: what the fit's interpolation relies on. Returns
// the sample count.
inline size_t measured_curve_input(std::string_view text, const std::string& source) {
  const MeasuredCurve c = parse_measured_curve(text, source);
  require(c.x.size() >= 2, "curve accepted with fewer than 2 samples");
  for (size_t i = 0; i < c.x.size(); ++i) {
    require(std::isfinite(c.x[i]), "curve accepted with a non-finite abscissa");
    require(i == 0 || c.x[i] > c.x[i - 1], "curve accepted with an abscissa that does not increase");
  }
  require(!c.columns.empty() && c.columns.size() == c.force.size(), "curve accepted without force columns");
  for (size_t k = 0; k < c.columns.size(); ++k) {
    const std::string& name = c.columns[k];
    require(name == "force" || name == "fx" || name == "fy" || name == "fz", "curve accepted with column " + name);
    require(std::count(c.columns.begin(), c.columns.end(), name) == 1, "curve accepted with a column twice");
    require(c.force[k].size() == c.x.size(), "a force column's length differs from the samples'");
    for (double f : c.force[k]) require(std::isfinite(f), "curve accepted with a non-finite force");
  }
  return c.x.size();
}

// kind sweep_files: the files `organsim sweep --collect` (and a shard) read
// back from a sweep's folder, one harness for all three, told apart by
// content: an object with "cases" is OUTDIR/cases.json (parse_plan), one
// with "status" a case's status.json (parse_case_status), anything else a
// case's forces.json (force_log_summary). An accepted plan or status
// survives a write and read back unchanged (shards and reruns read what was
// written); an accepted force log has one force of three numbers or nulls
// per time (checked here on the JSON itself) and gives a row whose sample
// count is its times' and whose forces are magnitudes (not negative, or
// null). Returns the cases, 1 for a status (0 when refused: the case is run
// again), or the samples.
inline size_t sweep_files_input(std::string_view text, const std::string& source) {
  const std::string s(text);
  const nlohmann::json j = nlohmann::json::parse(s, nullptr, false);
  if (j.is_object() && j.contains("cases")) {
    const Sweep plan = parse_plan(s, source);
    require(plan_json(parse_plan(plan_json(plan).dump(), "again.json")) == plan_json(plan),
            "plan round trip changed the plan");
    return plan.cases.size();
  }
  if (j.is_object() && j.contains("status")) {
    const std::optional<CaseStatus> status = parse_case_status(s);
    if (!status) return 0;
    const std::optional<CaseStatus> again = parse_case_status(to_json(*status).dump());
    require(again && to_json(*again) == to_json(*status), "status round trip changed the status");
    return 1;
  }
  const std::vector<double> at_times = {0.0, 0.05, 1.0};
  const ForceLogSummary log = force_log_summary(s, source, at_times);
  const nlohmann::json& forces = j["samples"]["force"];
  const size_t samples = j["samples"]["t"].size();
  require(forces.size() == samples, "force log accepted with another count of forces than of times");
  for (const nlohmann::json& f : forces) {
    require(f.is_array() && f.size() == 3, "force log accepted with a force that is not three values");
    for (const nlohmann::json& v : f)
      require(v.is_number() || v.is_null(), "force log accepted with a force value " + v.dump());
  }
  require(log.figures["samples"] == samples, "force log row with another sample count");
  std::vector<std::string> magnitudes = {"peak_force"};
  for (double t : at_times) magnitudes.push_back(force_at_name(t));
  for (const std::string& f : magnitudes) {
    const nlohmann::json& v = log.figures[f];
    require(v.is_null() || (v.is_number() && v.get<double>() >= 0), "force log row with " + f + " " + v.dump());
  }
  return samples;
}

// kind client_transform: the JSON matrix of `organsim serve
// --client-transform` (parse_client_transform). An accepted matrix is a
// rigid motion the pose and reply conversions can trust: finite, last row
// 0 0 0 1, an upper 3x3 orthonormal within 1e-6 with determinant +1.
// Returns 16 (its entries).
inline size_t client_transform_input(std::string_view text, const std::string& source) {
  const Matrix4 m = parse_client_transform(text, source);
  require(m.allFinite(), "transform accepted with a non-finite entry");
  require(m.row(3) == Eigen::RowVector4d(0, 0, 0, 1), "transform accepted without the last row 0 0 0 1");
  const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
  const Eigen::Matrix3d gram = r.transpose() * r;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k)
      require(std::abs(gram(i, k) - (i == k ? 1.0 : 0.0)) <= 1e-6, "transform accepted with a non-orthonormal 3x3");
  require(r.determinant() > 0, "transform accepted with a reflection");
  return static_cast<size_t>(m.size());
}

// kind igtl: the OpenIGTLink byte stream a client sends to `organsim serve`
// (IgtlStream). Any bytes give messages, refusals or a broken stream, never
// an exception or a crash; the same bytes cut into 7-byte pieces (as TCP may
// deliver them) give the same messages; an accepted TRANSFORM has the last
// row of a transform; an accepted STRING's text goes through the session's
// command parser (parse_client_command), which refuses or accepts it but
// never throws, and whose refusal prints no control character.
inline std::vector<IgtlMessage> igtl_input(std::string_view bytes) {
  const auto* data = reinterpret_cast<const uint8_t*>(bytes.data());
  IgtlStream whole;
  whole.append(data, bytes.size());
  std::vector<IgtlMessage> once;
  while (auto m = whole.next()) once.push_back(*m);
  IgtlStream pieces;
  std::vector<IgtlMessage> cut;
  for (size_t at = 0; at < bytes.size(); at += 7) {
    pieces.append(data + at, std::min<size_t>(7, bytes.size() - at));
    while (auto m = pieces.next()) cut.push_back(*m);
  }
  require(once.size() == cut.size() && whole.broken() == pieces.broken(),
          "the stream read whole and in pieces gave different messages");
  for (size_t i = 0; i < once.size(); ++i) {
    const IgtlMessage &a = once[i], &b = cut[i];
    require(a.transform == b.transform && a.text == b.text && a.content == b.content &&
                a.refused_kind == b.refused_kind && a.type == b.type && a.device == b.device &&
                std::memcmp(a.matrix.data(), b.matrix.data(), sizeof a.matrix) == 0,
            "message " + std::to_string(i) + " differs read whole and in pieces");
    require(!(a.transform && a.text), "a message is both a TRANSFORM and a STRING");
    require((a.transform || a.text) == a.refused_kind.empty(), "a message is neither or both of accepted and refused");
    if (a.transform)
      require(a.matrix[12] == 0 && a.matrix[13] == 0 && a.matrix[14] == 0 && a.matrix[15] == 1,
              "accepted TRANSFORM without the last row 0 0 0 1");
    if (a.text) {
      const ParsedCommand command = parse_client_command(a.content);
      if (const auto* why = std::get_if<std::string>(&command))
        for (char c : *why) require(static_cast<unsigned char>(c) >= 0x20, "a command refusal prints a control character");
    }
  }
  return once;
}

}  // namespace organsim::fuzz
