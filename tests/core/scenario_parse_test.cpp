// Scenario parsing: defaults, path resolution, and errors that name the JSON path.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <cmath>
#include <fstream>

#include "core/mesh/tet_mesh.h"
#include "core/model/model.h"
#include "core/model/stiffness.h"
#include "core/scenario/scenario.h"
#include "core/util/error.h"

namespace organsim {
namespace scenario_parse_test {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// A minimal valid scenario: only the mesh is required.
json minimal() { return json::parse(R"({"mesh": {"tet": "cube.mesh"}})"); }

Scenario parse(const json& j) { return parse_scenario(j, "/data/scenes", "scene.json"); }

// Parses j and returns the error message; fails the test if it parses.
std::string error_of(const json& j, ErrorKind expected_kind = ErrorKind::Scenario) {
  try {
    parse(j);
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), expected_kind) << e.what();
    return e.what();
  }
  ADD_FAILURE() << "parsed without error: " << j.dump();
  return "";
}

TEST(ScenarioParse, DefaultsAreAppliedAndDocumentedValues) {
  const Scenario s = parse(minimal());
  EXPECT_EQ(s.mesh.kind, MeshDef::Kind::Tet);
  EXPECT_EQ(s.mesh.path, fs::path("/data/scenes/cube.mesh"));
  EXPECT_DOUBLE_EQ(s.mesh.scale, 1.0);
  // Defaults stated in docs/scenarios.md.
  EXPECT_DOUBLE_EQ(s.material.density, 1060.0);
  EXPECT_DOUBLE_EQ(s.material.young_modulus, 3000.0);
  EXPECT_FALSE(s.material.spring_stiffness.has_value());
  EXPECT_DOUBLE_EQ(s.material.volume_modulus, 0.0);
  EXPECT_TRUE(s.fixed.empty());
  EXPECT_EQ(s.gravity, Vec3(0, 0, -9.81));
  EXPECT_DOUBLE_EQ(s.time.duration, 1.0);
  EXPECT_DOUBLE_EQ(s.time.dt, 1e-4);
  EXPECT_EQ(s.time.substeps, 10);
  EXPECT_EQ(s.time.ticks(), 1000);  // 1 s at a 1 ms tick
  EXPECT_FALSE(s.tool.has_value());
  EXPECT_EQ(s.backend.name, "auto");  // the fastest backend here, chosen at run time
  EXPECT_FALSE(s.backend.precision.has_value());
  EXPECT_TRUE(s.outputs.forces);
  EXPECT_FALSE(s.outputs.frames.has_value());
  EXPECT_FALSE(s.outputs.wants_rendering());
}

TEST(ScenarioParse, FullScenarioRoundTripsEveryField) {
  const json j = json::parse(R"({
    "description": "all fields",
    "mesh": {"surface": "../meshes/liver.off", "scale": 0.001,
             "options": {"target_points": 2500, "facet_distance": 0.0005, "exude": false}},
    "material": {"density": 1000, "spring_stiffness": 50, "spring_damping_time": 0.01,
                 "viscous_damping": 2, "volume_modulus": 1e4},
    "fixed": [{"box": {"min": [0,0,0], "max": [1,1,0.1]}},
              {"plane": {"point": [0,0,0], "normal": [0,0,-2]}},
              {"sphere": {"center": [1,2,3], "radius": 0.5}},
              {"indices": [0, 5, 7]}],
    "gravity": [0, 0, 0],
    "time": {"duration": 0.5, "dt": 5e-5, "substeps": 20},
    "tool": {"shape": "sphere", "radius": 0.02, "contact_stiffness": 300, "mode": "pull",
             "grasp_radius": 0.03, "grasp_time": 0.1, "release_time": 0.4,
             "keyframes": [{"t": 0, "position": [0,0,1]}, {"t": 0.5, "position": [0,0,2]}]},
    "backend": {"name": "gl", "precision": "float", "threads": 2},
    "outputs": {"forces": false,
                "frames": {"rate": 50, "size": [320, 240],
                           "camera": {"position": [1,0,0], "target": [0,0,0], "up": [0,0,1], "fov_deg": 30},
                           "style": {"wireframe": true, "colormap": "strain", "background": [0, 0.5, 1]}},
                "video": {"file": "run.avi", "codec": "MJPG"},
                "contact_sheet": {"frames": 8, "columns": 4}}
  })");
  const Scenario s = parse(j);
  EXPECT_EQ(s.mesh.kind, MeshDef::Kind::Surface);
  EXPECT_EQ(s.mesh.path, fs::path("/data/meshes/liver.off"));  // relative to the scenario's folder
  EXPECT_DOUBLE_EQ(s.mesh.scale, 0.001);
  EXPECT_EQ(s.mesh.target_points.value(), 2500);
  EXPECT_FALSE(s.mesh.cell_size.has_value());
  EXPECT_DOUBLE_EQ(s.mesh.facet_distance.value(), 0.0005);
  EXPECT_FALSE(s.mesh.exude);
  EXPECT_DOUBLE_EQ(s.material.spring_stiffness.value(), 50);
  EXPECT_DOUBLE_EQ(s.material.volume_modulus, 1e4);
  ASSERT_EQ(s.fixed.size(), 4u);
  EXPECT_EQ(s.fixed[0].kind, FixedSelector::Kind::Box);
  EXPECT_EQ(s.fixed[1].kind, FixedSelector::Kind::Plane);
  EXPECT_NEAR(s.fixed[1].normal.z(), -1.0, 1e-15);  // normalised
  EXPECT_EQ(s.fixed[2].kind, FixedSelector::Kind::Sphere);
  EXPECT_DOUBLE_EQ(s.fixed[2].radius, 0.5);
  EXPECT_EQ(s.fixed[3].indices, (std::vector<int32_t>{0, 5, 7}));
  EXPECT_EQ(s.gravity, Vec3(0, 0, 0));
  EXPECT_EQ(s.time.substeps, 20);
  EXPECT_EQ(s.time.ticks(), 500);  // 0.5 s / (5e-5 s * 20)
  ASSERT_TRUE(s.tool.has_value());
  EXPECT_EQ(s.tool->spec.mode, ToolMode::Pull);
  EXPECT_DOUBLE_EQ(s.tool->spec.release_time.value(), 0.4);
  ASSERT_EQ(s.tool->spec.keyframes.size(), 2u);
  EXPECT_EQ(s.tool->spec.keyframes[1].position, Vec3(0, 0, 2));
  EXPECT_EQ(s.backend.name, "gl");
  EXPECT_EQ(s.backend.precision.value(), "float");
  EXPECT_EQ(s.backend.threads, 2);
  EXPECT_FALSE(s.outputs.forces);
  ASSERT_TRUE(s.outputs.frames.has_value());
  EXPECT_EQ(s.outputs.frames->size[0], 320);
  EXPECT_FALSE(s.outputs.frames->camera.auto_fit);
  EXPECT_DOUBLE_EQ(s.outputs.frames->camera.fov_deg, 30);
  EXPECT_EQ(s.outputs.frames->style.colormap, Colormap::Strain);
  EXPECT_DOUBLE_EQ(s.outputs.frames->style.background[2], 1.0);
  ASSERT_TRUE(s.outputs.video.has_value());
  EXPECT_EQ(s.outputs.video->codec, "MJPG");
  EXPECT_DOUBLE_EQ(s.outputs.video->fps, 50);  // defaults to the frame rate
  EXPECT_EQ(s.outputs.contact_sheet->columns, 4);
}

TEST(ScenarioParse, BackendShorthandAndAutoCamera) {
  json j = minimal();
  j["backend"] = "gl";
  j["outputs"] = json::parse(R"({"frames": {"camera": "auto"}, "video": {}})");
  const Scenario s = parse(j);
  EXPECT_EQ(s.backend.name, "gl");
  EXPECT_TRUE(s.outputs.frames->camera.auto_fit);
  EXPECT_EQ(s.outputs.video->file, "video.mp4");
  EXPECT_EQ(s.outputs.video->codec, "mp4v");
  EXPECT_DOUBLE_EQ(s.outputs.video->fps, 30.0);
}

TEST(ScenarioParse, LabelColormapTakesNoScaleTopAndImageMeshesMayTargetAroundALabelsSize) {
  json j = minimal();
  j["outputs"] = json::parse(R"({"frames": {"style": {"colormap": "label"}}})");
  EXPECT_EQ(parse(j).outputs.frames->style.colormap, Colormap::Label);
  j["outputs"]["frames"]["style"]["colormap_max"] = 0.01;
  EXPECT_EQ(error_of(j), "scene.json: outputs.frames.style.colormap_max: expected no colormap_max with colormap \"label\"");
  // A target point count with one label's own size (the target sizes the
  // rest); with a size for every label it is refused.
  json m = json::parse(R"({"mesh": {"image": "seg.nii", "options": {"target_points": 2000, "label_cell_size": {"2": 0.0015}}}})");
  const Scenario s = parse(m);
  EXPECT_EQ(s.mesh.target_points, 2000);
  EXPECT_DOUBLE_EQ(s.mesh.label_cell_size.at(2), 0.0015);
  m["mesh"]["options"]["cell_size"] = 0.003;
  EXPECT_EQ(error_of(m), "scene.json: mesh.options: give target_points or cell_size, not both");
}

TEST(ScenarioParse, WrongTypeNamesTheJsonPath) {
  json j = minimal();
  j["tool"] = json::parse(R"({"keyframes": [{"t": 0, "position": [0,0,0]}, {"t": 1, "position": [0,0,0]},
                                            {"t": "late", "position": [0,0,0]}]})");
  EXPECT_EQ(error_of(j), "scene.json: tool.keyframes[2].t: expected a number, got a string");

  j = minimal();
  j["time"] = {{"substeps", 2.5}};
  EXPECT_EQ(error_of(j), "scene.json: time.substeps: expected an integer, got 2.5");

  j = minimal();
  j["gravity"] = {0, 0};
  EXPECT_EQ(error_of(j), "scene.json: gravity: expected an array of 3 numbers, got an array of 2");

  j = minimal();
  j["material"] = json::array();
  EXPECT_EQ(error_of(j), "scene.json: material: expected an object, got an array");

  j = minimal();
  j["fixed"] = json::parse(R"([{"box": {"min": [0,0,0], "max": [1,"x",1]}}])");
  EXPECT_EQ(error_of(j), "scene.json: fixed[0].box.max[1]: expected a number, got a string");
}

TEST(ScenarioParse, UnknownFieldNamesTheJsonPath) {
  json j = minimal();
  j["materail"] = json::object();
  EXPECT_EQ(error_of(j), "scene.json: materail: unknown field");

  j = minimal();
  j["outputs"] = json::parse(R"({"frames": {"style": {"wirefram": true}}})");
  EXPECT_EQ(error_of(j), "scene.json: outputs.frames.style.wirefram: unknown field");

  j = minimal();
  j["fixed"] = json::parse(R"([{"cylinder": {}}])");
  EXPECT_EQ(error_of(j), "scene.json: fixed[0].cylinder: unknown field");
}

TEST(ScenarioParse, MissingRequiredNamesTheJsonPath) {
  EXPECT_EQ(error_of(json::object()), "scene.json: mesh: missing (required)");
  json j = minimal();
  j["tool"] = json::parse(R"({"radius": 0.01})");
  EXPECT_EQ(error_of(j), "scene.json: tool.keyframes: missing (required)");
  j["tool"] = json::parse(R"({"keyframes": [{"t": 0}]})");
  EXPECT_EQ(error_of(j), "scene.json: tool.keyframes[0].position: missing (required)");
  j = minimal();
  j["mesh"] = json::object();
  EXPECT_NE(error_of(j).find("scene.json: mesh: missing \"surface\""), std::string::npos);
}

TEST(ScenarioParse, OutOfRangeNamesTheJsonPathAndValue) {
  json j = minimal();
  j["time"] = {{"dt", 0}};
  EXPECT_EQ(error_of(j), "scene.json: time.dt: expected a value > 0 (got 0)");
  j["time"] = {{"substeps", 0}};
  EXPECT_EQ(error_of(j), "scene.json: time.substeps: expected an integer >= 1 (got 0)");
  j = minimal();
  j["material"] = {{"density", -5}};
  EXPECT_EQ(error_of(j), "scene.json: material.density: expected a value > 0 (got -5)");
  j["material"] = {{"viscous_damping", -1}};
  EXPECT_EQ(error_of(j), "scene.json: material.viscous_damping: expected a value >= 0 (got -1)");
  j = minimal();
  j["tool"] = json::parse(R"({"radius": -0.01, "keyframes": [{"t": 0, "position": [0,0,0]}]})");
  EXPECT_EQ(error_of(j), "scene.json: tool.radius: expected a value > 0 (got -0.01)");
  j = minimal();
  j["fixed"] = json::parse(R"([{"sphere": {"center": [0,0,0], "radius": 0}}])");
  EXPECT_EQ(error_of(j), "scene.json: fixed[0].sphere.radius: expected a value > 0 (got 0)");
  j = minimal();
  j["backend"] = "cuda";
  EXPECT_EQ(error_of(j), "scene.json: backend: expected \"auto\", \"cpu\" or \"gl\" (got \"cuda\")");
  j = minimal();
  j["outputs"] = json::parse(R"({"frames": {"size": [8, 480]}})");
  EXPECT_EQ(error_of(j), "scene.json: outputs.frames.size[0]: expected a size in 16..8192 pixels (got 8)");
}

TEST(ScenarioParse, MeshUnitsSetTheScale) {
  json j = json::parse(R"({"mesh": {"surface": "organ_mm.vtk", "units": "mm"}})");
  Scenario s = parse(j);
  EXPECT_EQ(s.mesh.units, "mm");
  EXPECT_DOUBLE_EQ(s.mesh.scale, 0.001);
  j["mesh"]["units"] = "cm";
  EXPECT_DOUBLE_EQ(parse(j).mesh.scale, 0.01);
  j["mesh"]["units"] = "inch";
  EXPECT_EQ(error_of(j), "scene.json: mesh.units: expected \"mm\", \"cm\" or \"m\" (got \"inch\")");
  j["mesh"]["units"] = "mm";
  j["mesh"]["scale"] = 0.001;
  EXPECT_EQ(error_of(j), "scene.json: mesh: give \"units\" or \"scale\", not both");
}

TEST(ScenarioParse, KeyframesMustBeSortedByTime) {
  json j = minimal();
  j["tool"] = json::parse(R"({"keyframes": [{"t": 0, "position": [0,0,0]}, {"t": 0.6, "position": [0,0,0]},
                                            {"t": 0.5, "position": [0,0,1]}]})");
  const std::string e = error_of(j);
  EXPECT_EQ(e.rfind("scene.json: tool.keyframes[2].t: keyframes must be sorted", 0), 0u) << e;
  j["tool"]["keyframes"][2]["t"] = 0.6;  // equal times are not increasing either
  EXPECT_NE(error_of(j).find("tool.keyframes[2].t"), std::string::npos);
}

TEST(ScenarioParse, InconsistentCombinationsAreRejected) {
  json j = minimal();
  j["material"] = {{"young_modulus", 3000}, {"spring_stiffness", 10}};
  EXPECT_EQ(error_of(j), "scene.json: material: give young_modulus or spring_stiffness, not both");
  j = minimal();
  j["tool"] = json::parse(R"({"grasp_time": 0.1, "keyframes": [{"t": 0, "position": [0,0,0]}]})");
  EXPECT_EQ(error_of(j), "scene.json: tool.grasp_time: only used with \"mode\": \"pull\"");
  j = minimal();
  j["tool"] = json::parse(R"({"mode": "pull", "grasp_time": 0.5, "release_time": 0.2,
                              "keyframes": [{"t": 0, "position": [0,0,0]}]})");
  EXPECT_NE(error_of(j).find("tool.release_time: expected a time after grasp_time"), std::string::npos);
  j = minimal();
  j["outputs"] = json::parse(R"({"video": {}})");
  EXPECT_EQ(error_of(j), "scene.json: outputs.video: needs outputs.frames (the images it is made of)");
  j = minimal();
  j["mesh"]["options"] = {{"target_points", 1000}};
  EXPECT_EQ(error_of(j), "scene.json: mesh.options: meshing options apply only to a \"surface\" or \"image\" mesh");
  j = minimal();
  j["fixed"] = json::parse(R"([{"box": {"min": [0,0,0], "max": [1,1,1]}, "indices": [1]}])");
  EXPECT_NE(error_of(j).find("fixed[0]: expected exactly one of"), std::string::npos);
}

TEST(ScenarioLoad, PathsAreRelativeToTheScenarioFile) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "scenario_load" / "nested";
  fs::create_directories(dir);
  const fs::path file = dir / "s.json";
  std::ofstream(file) << R"({"mesh": {"tet": "../meshes/box.vtk"}})";
  const Scenario s = load_scenario(file);
  EXPECT_EQ(s.mesh.path, (dir.parent_path() / "meshes" / "box.vtk").lexically_normal());
  EXPECT_EQ(s.file, file);
}

TEST(ScenarioLoad, InvalidJsonGivesLineAndColumn) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "scenario_load";
  fs::create_directories(dir);
  const fs::path file = dir / "broken.json";
  std::ofstream(file) << "{\n  \"mesh\": {\"tet\": \"a.mesh\"},\n  \"time\": {\"dt\": }\n}\n";
  try {
    load_scenario(file);
    FAIL() << "broken JSON parsed";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("broken.json: invalid JSON at line 3"), std::string::npos) << e.what();
  }
  try {
    load_scenario(dir / "absent.json");
    FAIL() << "missing file loaded";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("absent.json: no such file"), std::string::npos) << e.what();
  }
}

TEST(ScenarioParse, ToolContactIsReadAndChecked) {
  json j = minimal();
  j["tool"] = json::parse(R"({"keyframes": [{"t": 0, "position": [0,0,0]}]})");
  EXPECT_EQ(parse(j).tool->spec.contact, ToolContact::Surface);  // absent: the surface triangles
  j["tool"]["contact"] = "points";
  EXPECT_EQ(parse(j).tool->spec.contact, ToolContact::Points);
  j["tool"]["contact"] = "surface";
  EXPECT_EQ(parse(j).tool->spec.contact, ToolContact::Surface);
  j["tool"]["contact"] = "triangles";
  EXPECT_NE(error_of(j).find("tool.contact: expected"), std::string::npos) << error_of(j);
  j["tool"]["contact"] = "points";
  j["tool"]["mode"] = "pull";
  EXPECT_EQ(error_of(j), "scene.json: tool.contact: only used with \"mode\": \"push\"");
}

// --- material.poisson_ratio, volume_formulation, shear_formulation ------------
// Each read, its refusal naming the field, and the value carried into the
// Model that build_model makes from the parsed material (a 2 x 2 x 2 box of
// 48 tets), so a parse branch that is dropped or maps to the wrong form shows.

Model model_of(const json& j) {
  return build_model(make_box_tet_mesh(Vec3::Zero(), Vec3::Constant(0.02), 2, 2, 2), parse(j).material, ModelOptions{});
}

// poisson_ratio 0.45 with E = 8 kPa: from 1/4 up the springs carry
// E_s = 2.5 E / (2 (1 + nu)) = 6896.55 Pa and the nodal volume term
// K = E (4 nu - 1) / (2 (1 + nu) (1 - 2 nu)) = 22068.97 Pa (docs/validation.md,
// "material.poisson_ratio"; the constants are written out here, not taken
// from core/model/stiffness.h); every point's nodal stiffness times its rest
// volume is K. Below 1/4 (0.1) the shear element is on and no volume term.
TEST(ScenarioParse, PoissonRatioIsReadCheckedAndReachesTheModel) {
  json j = minimal();
  EXPECT_FALSE(parse(j).material.poisson_ratio.has_value());  // absent: springs plus volume_modulus
  j["material"] = {{"young_modulus", 8000}, {"poisson_ratio", 0.45}};
  EXPECT_DOUBLE_EQ(*parse(j).material.poisson_ratio, 0.45);
  const Model m = model_of(j);
  ASSERT_TRUE(m.material.poisson_ratio.has_value());
  EXPECT_DOUBLE_EQ(*m.material.poisson_ratio, 0.45);
  const double k_nodal = 8000 * (4 * 0.45 - 1) / (2 * 1.45 * (1 - 0.9));
  EXPECT_NEAR(k_nodal, 22068.97, 0.01);
  EXPECT_NEAR(spring_modulus(m.material), 2.5 * 8000 / (2 * 1.45), 1e-9);
  ASSERT_EQ(m.point_volume_k.size(), static_cast<size_t>(m.npoint()));
  EXPECT_TRUE(m.tet_k.empty());
  EXPECT_TRUE(m.tet_shear_k.empty());
  for (int32_t a = 0; a < m.npoint(); ++a)
    EXPECT_NEAR(m.point_volume_k[a] * m.point_rest_volume[a], k_nodal, 1e-9 * k_nodal) << a;
  // 0 and 0.2: the shear element, no volume term.
  for (double nu : {0.0, 0.2}) {
    j["material"]["poisson_ratio"] = nu;
    EXPECT_DOUBLE_EQ(*parse(j).material.poisson_ratio, nu);
    const Model low = model_of(j);
    EXPECT_EQ(low.tet_shear_k.size(), low.tet_points.size()) << nu;
    EXPECT_TRUE(low.tet_k.empty() && low.point_volume_k.empty()) << nu;
  }
  for (double nu : {-0.01, 0.5, 0.7}) {
    j["material"]["poisson_ratio"] = nu;
    EXPECT_NE(error_of(j).find("scene.json: material.poisson_ratio: expected a number in [0, 0.5)"), std::string::npos)
        << nu;
  }
  j["material"] = {{"poisson_ratio", "0.3"}};
  EXPECT_NE(error_of(j).find("material.poisson_ratio"), std::string::npos) << error_of(j);
  j["material"] = {{"poisson_ratio", 0.3}, {"volume_modulus", 1000}};
  EXPECT_NE(error_of(j).find("give poisson_ratio or volume_modulus, not both"), std::string::npos);
  j["material"] = {{"poisson_ratio", 0.3}, {"spring_stiffness", 50}};
  EXPECT_NE(error_of(j).find("poisson_ratio needs young_modulus, not spring_stiffness"), std::string::npos);
}

TEST(ScenarioParse, VolumeFormulationIsReadCheckedAndReachesTheModel) {
  json j = minimal();
  EXPECT_FALSE(parse(j).material.volume_formulation.has_value());  // absent: the material's default
  j["material"] = {{"volume_modulus", 2000}, {"volume_formulation", "nodal"}};
  EXPECT_EQ(*parse(j).material.volume_formulation, VolumeFormulation::Nodal);
  Model m = model_of(j);
  EXPECT_EQ(m.point_volume_k.size(), static_cast<size_t>(m.npoint()));
  EXPECT_TRUE(m.tet_k.empty());
  j["material"]["volume_formulation"] = "per_tet";
  EXPECT_EQ(*parse(j).material.volume_formulation, VolumeFormulation::PerTet);
  m = model_of(j);
  EXPECT_EQ(m.tet_k.size(), m.tet_points.size());
  EXPECT_TRUE(m.point_volume_k.empty());
  // Per tet, each tet's stiffness times its rest volume is volume_modulus.
  for (size_t t = 0; t < m.tet_k.size(); ++t) EXPECT_NEAR(m.tet_k[t] * m.tet_rest_volume[t], 2000, 1e-9) << t;
  // With poisson_ratio the default is nodal, and per_tet overrides it.
  j["material"] = {{"poisson_ratio", 0.45}, {"volume_formulation", "per_tet"}};
  m = model_of(j);
  EXPECT_EQ(m.tet_k.size(), m.tet_points.size());
  EXPECT_TRUE(m.point_volume_k.empty());
  j["material"] = {{"volume_modulus", 2000}, {"volume_formulation", "tet"}};
  EXPECT_EQ(error_of(j), "scene.json: material.volume_formulation: expected \"per_tet\" or \"nodal\" (got \"tet\")");
  j["material"]["volume_formulation"] = 1;
  EXPECT_NE(error_of(j).find("material.volume_formulation"), std::string::npos) << error_of(j);
}

// Below nu = 1/4: smoothed by default (share 1/2 on node-averaged
// gradients, docs/physics.md), per_tet asks for the plain element (share 0).
TEST(ScenarioParse, ShearFormulationIsReadCheckedAndReachesTheModel) {
  json j = minimal();
  EXPECT_EQ(parse(j).material.shear_formulation, ShearFormulation::Smoothed);  // absent: smoothed
  j["material"] = {{"poisson_ratio", 0.1}};
  Model m = model_of(j);
  EXPECT_EQ(m.shear_smoothed_share, 0.5);
  EXPECT_EQ(m.point_shear_k.size(), static_cast<size_t>(m.npoint()));
  j["material"]["shear_formulation"] = "per_tet";
  EXPECT_EQ(parse(j).material.shear_formulation, ShearFormulation::PerTet);
  m = model_of(j);
  EXPECT_EQ(m.shear_smoothed_share, 0.0);
  EXPECT_TRUE(m.point_shear_k.empty());
  EXPECT_EQ(m.tet_shear_k.size(), m.tet_points.size());
  j["material"]["shear_formulation"] = "smoothed";
  EXPECT_EQ(parse(j).material.shear_formulation, ShearFormulation::Smoothed);
  EXPECT_EQ(model_of(j).shear_smoothed_share, 0.5);
  j["material"]["shear_formulation"] = "nodal";
  EXPECT_EQ(error_of(j), "scene.json: material.shear_formulation: expected \"smoothed\" or \"per_tet\" (got \"nodal\")");
}

// tool.hertz_layer: on by default for a pushing sphere on the surface (and
// only there), carried to the backend, may be turned off, and refused where
// it has no law (points, a grasper, a pulling tool).
TEST(ScenarioParse, HertzLayerIsReadAndRefusedWhereItHasNoLaw) {
  json j = minimal();
  j["tool"] = json::parse(R"({"keyframes": [{"t": 0, "position": [0,0,0]}]})");
  EXPECT_TRUE(parse(j).tool->spec.backend_tool().hertz_layer);
  j["tool"]["hertz_layer"] = false;
  EXPECT_FALSE(parse(j).tool->spec.backend_tool().hertz_layer);
  j["tool"].erase("hertz_layer");
  j["tool"]["contact"] = "points";
  EXPECT_FALSE(parse(j).tool->spec.hertz_layer);
  j["tool"].erase("contact");
  j["tool"]["mode"] = "pull";
  EXPECT_FALSE(parse(j).tool->spec.hertz_layer);
  j["tool"]["mode"] = "push";
  j["tool"]["hertz_layer"] = true;
  EXPECT_TRUE(parse(j).tool->spec.backend_tool().hertz_layer);
  j["tool"]["hertz_layer"] = "yes";
  EXPECT_NE(error_of(j).find("tool.hertz_layer: expected true or false"), std::string::npos) << error_of(j);
  j["tool"]["hertz_layer"] = true;
  j["tool"]["contact"] = "points";
  EXPECT_NE(error_of(j).find("tool.hertz_layer: the sub-cell layer is a pushing sphere's or capsule's surface contact"),
            std::string::npos)
      << error_of(j);
  // A capsule has its line layer, on by default; a grasper none.
  j["tool"]["contact"] = "surface";
  j["tool"].erase("hertz_layer");
  j["tool"]["shape"] = "capsule";
  j["tool"]["ends"] = json::parse("[[0, 0, 0], [0, 0, 0.1]]");
  EXPECT_TRUE(parse(j).tool->spec.backend_tool().hertz_layer);
  j["tool"]["hertz_layer"] = false;
  EXPECT_FALSE(parse(j).tool->spec.hertz_layer);
  j["tool"]["shape"] = "grasper";
  j["tool"]["friction"] = json::parse(R"({"static": 0.5, "kinetic": 0.4})");
  j["tool"]["keyframes"] = json::parse(R"([{"t": 0, "position": [0,0,0], "gap": 0.01}])");
  j["tool"].erase("hertz_layer");
  EXPECT_FALSE(parse(j).tool->spec.hertz_layer) << error_of(j);
  j["tool"]["hertz_layer"] = true;
  EXPECT_NE(error_of(j).find("tool.hertz_layer: the sub-cell"), std::string::npos) << error_of(j);
}

// A material of spring constants has no E: the layer is off by default
// there and refused when asked for.
TEST(ScenarioParse, HertzLayerNeedsAMaterialWithAYoungsModulus) {
  json j = minimal();
  j["material"] = json::parse(R"({"spring_stiffness": 50})");
  j["tool"] = json::parse(R"({"keyframes": [{"t": 0, "position": [0,0,0]}]})");
  EXPECT_FALSE(parse(j).tool->spec.hertz_layer);
  j["tool"]["hertz_layer"] = true;
  EXPECT_EQ(error_of(j), "scene.json: tool.hertz_layer: the sub-cell layer needs the material's young_modulus "
                         "(a spring_stiffness gives none)");
  j["material"] = json::parse(R"({"young_modulus": 5000})");
  EXPECT_TRUE(parse(j).tool->spec.hertz_layer);
}

// The capsule's fields and the keyframes' orientation: read, and every
// mistake refused with the path and what was expected.
TEST(ScenarioParse, CapsuleAndOrientationAreReadAndChecked) {
  json j = minimal();
  j["tool"] = json::parse(R"({"shape": "capsule", "radius": 0.0015, "ends": [[0, 0, 0], [0, 0, 0.1]],
                               "keyframes": [{"t": 0, "position": [0, 0, 0]},
                                             {"t": 1, "position": [0, 0, 0], "orientation": [0.7071068, 0, 0, 0.7071068]},
                                             {"t": 2, "position": [0, 0, 0],
                                              "axis_angle": {"axis": [0, 0, 2], "angle": 3.14159265358979}}]})");
  const ToolSpec s = parse(j).tool->spec;
  EXPECT_EQ(s.shape, ToolShape::Capsule);
  EXPECT_EQ(s.end_b, Vec3(0, 0, 0.1));
  EXPECT_DOUBLE_EQ(s.extent(), 0.1);
  EXPECT_EQ(s.keyframes[0].orientation.coeffs(), Quat::Identity().coeffs());  // absent: identity
  EXPECT_NEAR(s.keyframes[1].orientation.angularDistance(Quat(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitZ()))), 0, 1e-7);
  EXPECT_NEAR(s.keyframes[2].orientation.angularDistance(Quat(Eigen::AngleAxisd(M_PI, Vec3::UnitZ()))), 0, 1e-12);
  EXPECT_NEAR(s.keyframes[1].orientation.norm(), 1, 1e-15);  // normalised

  auto refused = [&](const char* patch, const std::string& want) {
    json k = j;
    k["tool"].merge_patch(json::parse(patch));
    EXPECT_EQ(error_of(k), want) << patch;
  };
  refused(R"({"shape": "cone"})",
          "scene.json: tool.shape: expected \"sphere\", \"capsule\" or \"grasper\" (got \"cone\")");
  refused(R"({"ends": [[0, 0, 0]]})",
          "scene.json: tool.ends: expected two end points [[x, y, z], [x, y, z]] in the tool frame, m");
  refused(R"({"ends": [[0, 0, 0.1], [0, 0, 0.1]]})",
          "scene.json: tool.ends: expected two different end points (a capsule of zero length is \"shape\": "
          "\"sphere\")");
  refused(R"({"shape": "sphere"})", "scene.json: tool.ends: only used with \"shape\": \"capsule\" or \"grasper\"");
  refused(R"({"mode": "pull"})", "scene.json: tool.shape: \"capsule\" is a pushing tool (\"mode\": \"push\")");
  refused(R"({"ends": null})", "scene.json: tool.ends: missing (required)");
  auto refused_key = [&](const json& keyframe, const std::string& want) {
    json k = j;
    k["tool"]["keyframes"][1] = keyframe;
    EXPECT_EQ(error_of(k), want) << keyframe.dump();
  };
  refused_key(json::parse(R"({"t": 1, "position": [0, 0, 0], "orientation": [1, 0, 0]})"),
              "scene.json: tool.keyframes[1].orientation: expected an array of 4 numbers, got an array of 3");
  refused_key(json::parse(R"({"t": 1, "position": [0, 0, 0], "orientation": [0, 90, 0, 0]})"),
              "scene.json: tool.keyframes[1].orientation: expected a unit quaternion [w, x, y, z] (got length "
              "90.000000)");
  refused_key(json::parse(R"({"t": 1, "position": [0, 0, 0], "orientation": [1, 0, 0, 0], "axis_angle": {}})"),
              "scene.json: tool.keyframes[1].axis_angle: give either \"orientation\" or \"axis_angle\", not both");
  refused_key(json::parse(R"({"t": 1, "position": [0, 0, 0], "axis_angle": {"axis": [0, 0, 0], "angle": 1}})"),
              "scene.json: tool.keyframes[1].axis_angle.axis: expected a non-zero axis [x, y, z]");
  refused_key(json::parse(R"({"t": 1, "position": [0, 0, 0], "axis_angle": {"axis": [0, 0, 1]}})"),
              "scene.json: tool.keyframes[1].axis_angle.angle: missing (required)");
  refused_key(json::parse(R"({"t": 1, "position": [0, 0, 0], "axis_angle": {"axis": [0, 0, 1], "angle": 1, "deg": 1}})"),
              "scene.json: tool.keyframes[1].axis_angle.deg: unknown field");
}

// A grasper: its jaws' midline, friction (required: it holds by friction;
// kinetic defaults to static), a gap on its first keyframe held by the
// keyframes without one and linear between them; friction on other shapes
// only with surface contact.
TEST(ScenarioParse, GrasperAndFrictionAreReadAndChecked) {
  json j = minimal();
  j["tool"] = json::parse(R"({"shape": "grasper", "radius": 0.0025, "ends": [[0, 0, 0], [0.02, 0, 0]],
                               "friction": {"static": 0.8, "kinetic": 0.5},
                               "keyframes": [{"t": 0, "position": [0, 0, 0], "gap": 0.03},
                                             {"t": 1, "position": [0, 0, 0], "gap": 0.01},
                                             {"t": 2, "position": [0, 0, 0.02]}]})");
  const ToolSpec s = parse(j).tool->spec;
  EXPECT_EQ(s.shape, ToolShape::Grasper);
  EXPECT_EQ(s.friction.mu_s, 0.8);
  EXPECT_EQ(s.friction.mu_k, 0.5);
  EXPECT_EQ(s.keyframes[2].gap, 0.01);  // held
  EXPECT_DOUBLE_EQ(s.gap_at(0.25), 0.025);
  EXPECT_DOUBLE_EQ(s.extent(), 0.02 + 0.015);  // the midline's far end and half the widest gap
  EXPECT_EQ(s.backend_tool().jaws(), 2);
  EXPECT_DOUBLE_EQ(s.backend_tool().stiffness_factor(), 2 + 1 + 2 * 0.8);
  {
    json k = j;
    k["tool"]["friction"] = json::parse(R"({"static": 0.6})");
    EXPECT_EQ(parse(k).tool->spec.friction.mu_k, 0.6);
  }
  auto refused = [&](const char* patch, const std::string& want) {
    json k = j;
    k["tool"].merge_patch(json::parse(patch));
    EXPECT_EQ(error_of(k), want) << patch;
  };
  refused(R"({"friction": null})", "scene.json: tool.friction: a grasper holds by friction: expected \"friction\": "
                                   "{\"static\": mu_s, \"kinetic\": mu_k}");
  refused(R"({"friction": {"static": 0.5, "kinetic": 0.7}})",
          "scene.json: tool.friction.kinetic: expected a kinetic coefficient at most the static one (0.500000)");
  refused(R"({"friction": {"static": null}})", "scene.json: tool.friction.static: missing (required)");
  refused(R"({"friction": {"static": 0.5, "dynamic": 0.3}})", "scene.json: tool.friction.dynamic: unknown field");
  refused(R"({"contact": "points"})",
          "scene.json: tool.contact: a grasper's jaws touch the surface (\"contact\": \"surface\")");
  refused(R"({"mode": "pull"})", "scene.json: tool.shape: \"grasper\" is a pushing tool (\"mode\": \"push\")");
  {
    json k = j;
    k["tool"]["keyframes"][0].erase("gap");
    EXPECT_EQ(error_of(k), "scene.json: tool.keyframes[0].gap: expected the grasper's jaw gap (m) on its first keyframe");
    k = j;
    k["tool"]["keyframes"][1]["gap"] = -0.01;
    EXPECT_EQ(error_of(k).rfind("scene.json: tool.keyframes[1].gap: ", 0), 0u) << error_of(k);
  }
  // Friction on a sphere: surface contact only; a gap means nothing to it.
  json sphere = minimal();
  sphere["tool"] = json::parse(R"({"radius": 0.01, "friction": {"static": 0.3},
                                    "keyframes": [{"t": 0, "position": [0, 0, 0]}]})");
  EXPECT_EQ(parse(sphere).tool->spec.friction.mu_s, 0.3);
  EXPECT_EQ(parse(sphere).tool->spec.backend_tool().stiffness_factor(), 1 + 1 + 2 * 0.3);
  json points = sphere;
  points["tool"]["contact"] = "points";
  EXPECT_EQ(error_of(points), "scene.json: tool.friction: friction acts on surface contact (\"mode\": \"push\", "
                              "\"contact\": \"surface\")");
  json gap = sphere;
  gap["tool"]["keyframes"][0]["gap"] = 0.01;
  EXPECT_EQ(error_of(gap), "scene.json: tool.keyframes[0].gap: only used with \"shape\": \"grasper\"");
}

// Orientation between keyframes: slerp, so a quarter turn is an eighth
// halfway (45 degrees about the same axis), and exactly each keyframe's
// orientation at its time and outside the keyframes.
TEST(ToolSpec, OrientationIsSlerpedBetweenKeyframesAndExactAtThem) {
  ToolSpec s;
  const Quat start(Eigen::AngleAxisd(0.2, Vec3(1, 2, 3).normalized()));
  const Quat quarter = Quat(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitZ())) * start;
  s.keyframes = {{0.5, Vec3::Zero(), start}, {1.5, Vec3::Zero(), quarter}, {2.5, Vec3::Zero()}};
  const Quat half = s.orientation_at(1.0);
  const Quat turned = half * start.inverse();  // the turn made so far
  EXPECT_NEAR(Eigen::AngleAxisd(turned).angle(), M_PI / 4, 1e-12);
  EXPECT_NEAR(std::abs(Eigen::AngleAxisd(turned).axis().z()), 1, 1e-12);
  EXPECT_NEAR(Eigen::AngleAxisd(s.orientation_at(0.75) * start.inverse()).angle(), M_PI / 8, 1e-12);
  for (double t : {0.0, 0.5}) EXPECT_EQ(s.orientation_at(t).coeffs(), start.coeffs()) << t;
  EXPECT_EQ(s.orientation_at(1.5).coeffs(), quarter.coeffs());
  for (double t : {2.5, 9.0}) EXPECT_EQ(s.orientation_at(t).coeffs(), Quat::Identity().coeffs()) << t;
  // q and -q are one rotation: slerp takes the short way between them.
  ToolSpec flipped;
  flipped.keyframes = {{0, Vec3::Zero(), Quat::Identity()}, {1, Vec3::Zero(), Quat(-1, 0, 0, 0)}};
  EXPECT_NEAR(flipped.orientation_at(0.5).angularDistance(Quat::Identity()), 0, 1e-12);
}

}  // namespace
}  // namespace scenario_parse_test
}  // namespace organsim

namespace organsim {
namespace scenario_parse_test {
namespace {

// time.integrator and the implicit solver's settings: defaults, values,
// and the settings refused where they mean nothing (Verlet) or are out of range.
TEST(ScenarioParse, IntegratorAndItsSolverSettingsAreReadAndChecked) {
  const Scenario d = parse(minimal());
  EXPECT_EQ(d.time.integrator, Integrator::Verlet);
  EXPECT_EQ(d.time.implicit.newton_iterations, 1);
  EXPECT_EQ(d.time.implicit.cg_tolerance, 1e-5);
  EXPECT_EQ(d.time.implicit.cg_max_iterations, 200);
  EXPECT_EQ(d.time.implicit.preconditioner, Preconditioner::BlockJacobi);

  json j = minimal();
  j["time"] = {{"dt", 1e-3}, {"substeps", 1}, {"integrator", "implicit_euler"}, {"newton_iterations", 3},
               {"cg_tolerance", 1e-7}, {"cg_max_iterations", 50}, {"preconditioner", "rest_cholesky"}};
  const Scenario s = parse(j);
  EXPECT_EQ(s.time.integrator, Integrator::ImplicitEuler);
  EXPECT_EQ(s.time.implicit.newton_iterations, 3);
  EXPECT_EQ(s.time.implicit.cg_tolerance, 1e-7);
  EXPECT_EQ(s.time.implicit.cg_max_iterations, 50);
  EXPECT_EQ(s.time.implicit.preconditioner, Preconditioner::RestCholesky);
  j["time"]["preconditioner"] = "two_level";
  EXPECT_EQ(parse(j).time.implicit.preconditioner, Preconditioner::TwoLevel);

  j = minimal();
  j["time"] = {{"integrator", "implicit_damping"}, {"cg_tolerance", 1e-6}};
  const Scenario damping = parse(j);
  EXPECT_EQ(damping.time.integrator, Integrator::ImplicitDamping);
  EXPECT_EQ(damping.time.implicit.cg_tolerance, 1e-6);
  j["time"] = {{"integrator", "implicit_damping"}, {"newton_iterations", 2}};
  EXPECT_NE(error_of(j).find("must be 1 with implicit_damping"), std::string::npos);

  j = minimal();
  j["time"] = {{"integrator", "rk4"}};
  EXPECT_NE(error_of(j).find("time.integrator"), std::string::npos);
  j["time"] = {{"cg_tolerance", 1e-6}};
  EXPECT_NE(error_of(j).find("applies only with \"integrator\": \"implicit_euler\" or \"implicit_damping\""),
            std::string::npos);
  j["time"] = {{"integrator", "implicit_euler"}, {"newton_iterations", 0}};
  EXPECT_NE(error_of(j).find("time.newton_iterations"), std::string::npos);
  j["time"] = {{"integrator", "implicit_euler"}, {"cg_max_iterations", 0}};
  EXPECT_NE(error_of(j).find("time.cg_max_iterations"), std::string::npos);
  j["time"] = {{"integrator", "implicit_euler"}, {"cg_tolerance", -1}};
  EXPECT_NE(error_of(j).find("time.cg_tolerance"), std::string::npos);
  j["time"] = {{"integrator", "implicit_euler"}, {"preconditioner", "ilu"}};
  EXPECT_NE(error_of(j).find("time.preconditioner"), std::string::npos);
  EXPECT_NE(error_of(j).find("\"block_jacobi\", \"two_level\" or \"rest_cholesky\""), std::string::npos);
}

}  // namespace
}  // namespace scenario_parse_test
}  // namespace organsim
