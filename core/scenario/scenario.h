#pragma once
// A scenario: which mesh, which material, what is fixed, how long and how
// finely to integrate, what the tool does and what to write. Parsed from JSON
// into definition structs with validated defaults; every error names the file
// and the JSON path. Field by field in docs/scenarios.md. SI units.
#include <nlohmann/json_fwd.hpp>

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/model/material.h"
#include "core/scenario/events.h"
#include "core/sim/reference_backend.h"
#include "core/sim/step_plan.h"
#include "core/scenario/outputs.h"
#include "core/scenario/tool_spec.h"
#include "core/util/vec.h"

namespace organsim {

// `mesh`: a closed surface meshed on the fly, or a tetrahedral mesh file.
struct MeshDef {
  enum class Kind { Surface, Tet, Image } kind = Kind::Tet;
  std::filesystem::path path;  // resolved against the scenario file's folder
  double scale = 1.0;          // coordinates are multiplied by this (e.g. 0.001 for mm input)
  std::string units = "m";     // the file's length unit as given ("mm", "cm", "m"); scale follows from it
  // Meshing options (Kind::Surface and Kind::Image), in metres after scaling.
  std::optional<int32_t> target_points;
  std::optional<double> cell_size;       // m
  std::optional<double> facet_distance;  // m
  bool exude = true;
  // Kind::Image only: the labels to mesh (empty: every label > 0), a cell
  // size per label (m), and whether `units`/`scale` were given (they apply
  // only when the image's header names no unit).
  std::vector<int32_t> labels;
  std::map<int32_t, double> label_cell_size;
  bool scale_given = false;
};

// `time`: the run lasts `duration`; one haptic tick is dt * substeps.
struct TimeDef {
  double duration = 1.0;   // s
  double dt = 1e-4;        // s, integration step
  int32_t substeps = 10;   // steps per tick
  double settle = 0;       // s before t = 0 to come to rest under gravity, no tool (0: start from the rest shape)
  // "integrator": "verlet" (explicit, dt below dt_crit) or "implicit_euler"
  // (any dt; core/sim/reference_backend.h), whose solver settings are
  // "newton_iterations", "cg_tolerance", "cg_max_iterations" and
  // "preconditioner" ("block_jacobi", "two_level" or "rest_cholesky").
  Integrator integrator = Integrator::Verlet;
  ImplicitOptions implicit;

  double tick() const { return dt * substeps; }   // s
  int64_t ticks() const;                         // ceil(duration / tick)
};

// `tool`: absent means no tool pass at all.
struct ToolDef {
  ToolSpec spec;  // sphere radius, stiffness, mode, grasp/release, keyframes
};

struct BackendDef {
  std::string name = "auto";             // "auto" (fastest here: app/backend_factory.h), "cpu" or "gl"
  std::optional<std::string> precision;  // "double" or "float"; default per backend
  int32_t threads = 0;                   // cpu: 0 = all hardware threads
};

inline constexpr double kDefaultGravityZ = -9.81;  // m/s^2, along -z

struct Scenario {
  std::filesystem::path file;  // the scenario file as given (for messages and the log)
  MeshDef mesh;
  Material material;                    // the first of `materials` when those are given
  std::vector<LabelMaterial> materials;  // per-label materials; empty: `material` everywhere
  std::vector<FixedSelector> fixed;
  Vec3 gravity{0, 0, kDefaultGravityZ};  // m/s^2; [0,0,0] switches the gravity pass off
  TimeDef time;
  std::optional<ToolDef> tool;
  BackendDef backend;
  OutputsDef outputs;
  EventsDef events;  // empty: no topology machinery at all
};

// Parses `j`; relative paths are resolved against `base_dir`; `source` names
// the file in messages. Throws Error(Scenario) naming the JSON path.
Scenario parse_scenario(const nlohmann::json& j, const std::filesystem::path& base_dir,
                        const std::string& source);

// Parses scenario JSON text (what load_scenario reads from the file; the
// fuzz harness enters here). Errors as load_scenario's.
Scenario parse_scenario_text(std::string_view text, const std::filesystem::path& base_dir,
                             const std::string& source);

// Reads and parses a scenario file. Throws Error(Input) for an unreadable file
// or invalid JSON (with line and column), Error(Scenario) for bad fields.
Scenario load_scenario(const std::filesystem::path& path);

// JSON paths of the fields that hold file names, resolved against the
// scenario file's folder ("mesh.surface", "mesh.image", "mesh.tet"): a tool that writes a
// scenario elsewhere (organsim sweep) makes these absolute.
const std::vector<std::string>& scenario_file_fields();

}  // namespace organsim
