// Scenario parsing: defaults, path resolution, and errors that name the JSON path.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

#include "core/scenario/scenario.h"
#include "core/util/error.h"

namespace organsim {
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

}  // namespace
}  // namespace organsim
