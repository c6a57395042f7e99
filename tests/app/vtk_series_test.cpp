// outputs.vtk: the ParaView series of a run, opened by VTK itself (Debian's
// python3-vtk9), with values checked against VTK's own geometry and physics.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "../core/vtk_client.h"
#include "core/mesh/mesh_io.h"
#include "tests/app/run_cli_test_util.h"

namespace organsim {
namespace vtk_series_test {
namespace {

namespace fs = std::filesystem;
using test::run_organsim;

fs::path scenario_in(const fs::path& dir, const nlohmann::json& extra) {
  fs::create_directories(dir);
  write_tet_mesh(dir / "box.vtu", make_box_tet_mesh(Vec3(0, 0, 0), Vec3(0.04, 0.04, 0.02), 4, 4, 2));
  nlohmann::json j = nlohmann::json::parse(R"({
    "mesh": {"tet": "box.vtu"},
    "material": {"young_modulus": 5000, "volume_modulus": 2000},
    "time": {"duration": 0.05, "dt": 0.0001, "substeps": 10},
    "backend": {"threads": 1},
    "outputs": {"vtk": {"rate": 100}}
  })");
  j.merge_patch(extra);
  std::ofstream(dir / "scene.json") << j.dump(2);
  return dir / "scene.json";
}

// Reads states.pvd (XML, parsed by Python) and every state with VTK; prints
// per state: t, points, cells, and the checks' largest errors.
const char* kSeriesReader = R"(
import xml.etree.ElementTree as ET, math, sys
rest_reader = vtk.vtkXMLUnstructuredGridReader(); rest_reader.SetFileName('box.vtu'); rest_reader.Update()
rest = rest_reader.GetOutput()
def volumes(g):
    f = vtk.vtkCellSizeFilter(); f.SetInputData(g); f.ComputeVolumeOn(); f.Update()
    return f.GetOutput().GetCellData().GetArray('Volume')
rest_volume = volumes(rest)
for ds in ET.parse('out/states.pvd').getroot().iter('DataSet'):
    r = vtk.vtkXMLUnstructuredGridReader(); r.SetFileName('out/' + ds.get('file')); r.Update()
    g = r.GetOutput(); pd = g.GetPointData(); cd = g.GetCellData()
    disp = pd.GetArray('displacement'); vel = pd.GetArray('velocity'); fixed = pd.GetArray('fixed')
    force = pd.GetArray('tool_force'); ratio = cd.GetArray('volume_ratio'); strain = cd.GetArray('max_spring_strain')
    # The current points minus the displacement are the rest points, in the input numbering.
    rest_error = max(abs(g.GetPoint(i)[c] - disp.GetTuple3(i)[c] - rest.GetPoint(i)[c])
                     for i in range(g.GetNumberOfPoints()) for c in range(3))
    vol = volumes(g)
    ratio_error = max(abs(ratio.GetValue(c) - vol.GetValue(c) / rest_volume.GetValue(c)) for c in range(g.GetNumberOfCells()))
    strain_error = 0.0
    for c in range(g.GetNumberOfCells()):
        ids = [g.GetCell(c).GetPointId(k) for k in range(4)]
        largest = 0.0
        for a in range(4):
            for b in range(a + 1, 4):
                L = math.dist(g.GetPoint(ids[a]), g.GetPoint(ids[b])); R = math.dist(rest.GetPoint(ids[a]), rest.GetPoint(ids[b]))
                largest = max(largest, abs(L - R) / R)
        strain_error = max(strain_error, abs(strain.GetValue(c) - largest))
    fixed_moved = max([0.0] + [math.hypot(*disp.GetTuple3(i)) for i in range(g.GetNumberOfPoints()) if fixed.GetValue(i)])
    nfixed = sum(1 for i in range(g.GetNumberOfPoints()) if fixed.GetValue(i))
    vz = sum(vel.GetTuple3(i)[2] for i in range(g.GetNumberOfPoints())) / g.GetNumberOfPoints()
    fz = sum(force.GetTuple3(i)[2] for i in range(g.GetNumberOfPoints())) if force else 0.0
    print(ds.get('timestep'), g.GetNumberOfPoints(), g.GetNumberOfCells(), rest_error, ratio_error, strain_error,
          fixed_moved, nfixed, vz, fz)
)";

struct State {
  double t = 0;
  size_t points = 0, cells = 0;
  double rest_error = 0, ratio_error = 0, strain_error = 0, fixed_moved = 0;
  int nfixed = 0;
  double mean_vz = 0, force_z = 0;
};

std::vector<State> read_series(const fs::path& dir) {
  std::istringstream in(testing::run_vtk_python(kSeriesReader, dir));
  std::vector<State> states;
  State s;
  while (in >> s.t >> s.points >> s.cells >> s.rest_error >> s.ratio_error >> s.strain_error >> s.fixed_moved >>
         s.nfixed >> s.mean_vz >> s.force_z) {
    states.push_back(s);
  }
  return states;
}

TEST(VtkSeries, FreeFallStatesOpenInVtkWithVelocityGt) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "vtk_series" / "free_fall";
  fs::remove_all(dir);
  const auto run = run_organsim("run " + scenario_in(dir, nlohmann::json::parse(R"({"material": {"viscous_damping": 0}})")).string() + " -o " + (dir / "out").string(), dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("states.pvd"), std::string::npos) << run.out;
  const std::vector<State> states = read_series(dir);
  // 0.05 s at 100 states per second: t = 0, 0.01, ..., 0.05.
  ASSERT_EQ(states.size(), 6u);
  for (size_t k = 0; k < states.size(); ++k) {
    const State& s = states[k];
    EXPECT_NEAR(s.t, 0.01 * static_cast<double>(k), 1e-9);
    EXPECT_EQ(s.points, 75u);  // 5 x 5 x 3
    EXPECT_EQ(s.cells, 192u);  // 4 x 4 x 2 cubes x 6 tets
    // Tolerances: positions are Float64 in the file, so rest points and
    // volume ratios agree to round-off (1e-12 m and 1e-9 relative).
    EXPECT_LT(s.rest_error, 1e-12) << s.t;
    EXPECT_LT(s.ratio_error, 1e-9) << s.t;
    EXPECT_LT(s.strain_error, 1e-9) << s.t;
    // Nothing is fixed: the block falls as one. The velocity is the mean over
    // the last 1 ms tick, i.e. g (t - 0.5 ms) up to the Verlet start-up error
    // (one step, 0.1 ms of g): 1 % of g t at t >= 10 ms covers both.
    EXPECT_EQ(s.nfixed, 0);
    const double expected = s.t > 0 ? -9.81 * (s.t - 0.0005) : 0.0;
    EXPECT_NEAR(s.mean_vz, expected, 0.01 * 9.81 * s.t + 1e-12) << s.t;
  }
}

TEST(VtkSeries, PushedBlockHasFixedBaseAndToolForceEqualToTheLoggedReaction) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "vtk_series" / "push";
  fs::remove_all(dir);
  // Base fixed, the tool presses 4 mm into the middle of the top face's edge
  // y = 0 and holds from 30 ms on. The edge's points weigh half the median
  // free point (a top face point), so the contact stiffness they get is
  // halved (Model::tool_k_scale): the file must show the force the backend
  // applied with that scale, not the scenario's bare stiffness.
  const nlohmann::json extra = nlohmann::json::parse(R"({
    "fixed": [{"plane": {"point": [0, 0, 0.001], "normal": [0, 0, -1]}}],
    "gravity": [0, 0, 0],
    "time": {"duration": 0.06},
    "tool": {"radius": 0.01, "contact_stiffness": 500,
             "keyframes": [{"t": 0, "position": [0.02, 0.0, 0.031]}, {"t": 0.03, "position": [0.02, 0.0, 0.026]}]}
  })");
  const auto run = run_organsim("run " + scenario_in(dir, extra).string() + " -o " + (dir / "out").string(), dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::vector<State> states = read_series(dir);
  ASSERT_EQ(states.size(), 7u);
  const State& last = states.back();
  EXPECT_EQ(last.nfixed, 25);  // the 5 x 5 base points
  EXPECT_EQ(last.fixed_moved, 0.0);
  EXPECT_LT(last.ratio_error, 1e-9);
  EXPECT_LT(last.strain_error, 1e-9);
  // The contact forces on the points add up to minus the reaction the force
  // log holds for the last tick. The log's reaction is from the last substep's
  // start, the file's from the tick's end: 0.1 ms apart with the tool at rest,
  // so they agree to 2 %.
  std::ifstream log(dir / "out" / "forces.json");
  const nlohmann::json forces = nlohmann::json::parse(log);
  const double logged_z = forces.at("samples").at("force").back().at(2).get<double>();
  ASSERT_GT(logged_z, 0.05);  // the block pushes the tool up with a real force
  EXPECT_NEAR(-last.force_z, logged_z, 0.02 * logged_z);
}

TEST(VtkSeries, SettledRunStartsAtRestUnderGravity) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "vtk_series" / "settle";
  fs::remove_all(dir);
  const nlohmann::json extra = nlohmann::json::parse(R"({
    "material": {"young_modulus": 3000},
    "fixed": [{"plane": {"point": [0, 0, 0.001], "normal": [0, 0, -1]}}],
    "time": {"duration": 0.03, "settle": 2.0}
  })");
  const auto run = run_organsim("run " + scenario_in(dir, extra).string() + " -o " + (dir / "out").string(), dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("settle:"), std::string::npos) << run.out;
  std::ifstream log(dir / "out" / "forces.json");
  const nlohmann::json meta = nlohmann::json::parse(log).at("meta");
  ASSERT_TRUE(meta.at("settle").is_object()) << meta.dump();
  EXPECT_TRUE(meta.at("settle").at("converged").get<bool>());
  const double sag = meta.at("settle").at("max_displacement_m").get<double>();
  EXPECT_GT(sag, 1e-4);
  // The series starts sagged (state 0 already displaced by the sag) and the
  // run moves nothing by more than 1 % of it: the largest displacement of
  // each state, read by VTK.
  const std::string out = testing::run_vtk_python(R"(
import xml.etree.ElementTree as ET, math
for ds in ET.parse('out/states.pvd').getroot().iter('DataSet'):
    r = vtk.vtkXMLUnstructuredGridReader(); r.SetFileName('out/' + ds.get('file')); r.Update()
    d = r.GetOutput().GetPointData().GetArray('displacement')
    print(max(math.hypot(*d.GetTuple3(i)) for i in range(d.GetNumberOfTuples())))
)", dir);
  std::istringstream in(out);
  std::vector<double> largest;
  for (double v; in >> v;) largest.push_back(v);
  ASSERT_EQ(largest.size(), 4u);  // t = 0, 0.01, 0.02, 0.03
  for (double v : largest) EXPECT_NEAR(v, sag, 0.01 * sag);
}

TEST(VtkSeries, SurfaceOnlyStatesHoldTheBoundaryWithTheUsersPointNumbers) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "vtk_series" / "surface";
  fs::remove_all(dir);
  const nlohmann::json extra = nlohmann::json::parse(R"({"time": {"duration": 0.02}, "outputs": {"vtk": {"surface_only": true}}})");
  const auto run = run_organsim("run " + scenario_in(dir, extra).string() + " -o " + (dir / "out").string(), dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::string out = testing::run_vtk_python(R"(
import xml.etree.ElementTree as ET
rr = vtk.vtkXMLUnstructuredGridReader(); rr.SetFileName('box.vtu'); rr.Update(); rest = rr.GetOutput()
files = [ds.get('file') for ds in ET.parse('out/states.pvd').getroot().iter('DataSet')]
r = vtk.vtkXMLPolyDataReader(); r.SetFileName('out/' + files[-1]); r.Update(); g = r.GetOutput()
ids = g.GetPointData().GetArray('point_id'); disp = g.GetPointData().GetArray('displacement')
err = max(abs(g.GetPoint(i)[c] - disp.GetTuple3(i)[c] - rest.GetPoint(int(ids.GetValue(i)))[c])
          for i in range(g.GetNumberOfPoints()) for c in range(3))
edges = vtk.vtkFeatureEdges(); edges.SetInputData(g); edges.BoundaryEdgesOn(); edges.NonManifoldEdgesOn()
edges.FeatureEdgesOff(); edges.ManifoldEdgesOff(); edges.Update()
print(len(files), files[-1], g.GetNumberOfPoints(), g.GetNumberOfPolys(), err, edges.GetOutput().GetNumberOfCells(),
      int(g.GetCellData().GetArray('label') is None))
)", dir);
  std::istringstream in(out);
  size_t nfiles = 0, points = 0, polys = 0, open_edges = 1;
  std::string last;
  double rest_error = 1;
  int no_label = 0;
  in >> nfiles >> last >> points >> polys >> rest_error >> open_edges >> no_label;
  EXPECT_EQ(nfiles, 3u);  // t = 0, 0.01, 0.02
  EXPECT_EQ(last, "vtk/state_00002.vtp");
  EXPECT_EQ(points, 66u);   // 75 points less the 3 x 3 x 1 inside
  EXPECT_EQ(polys, 128u);   // 64 boundary squares, 2 triangles each
  EXPECT_LT(rest_error, 1e-12);  // Float64 positions: round-off only
  EXPECT_EQ(open_edges, 0u);     // VTK finds the surface closed and manifold
  EXPECT_EQ(no_label, 1);        // an unlabelled mesh: no label array
}

TEST(VtkSeries, LabelledMeshCarriesEachTetsLabelAndEachSurfaceTrianglesTets) {
  // The box with label 1 for x < 2 cm and label 2 beyond, as a labelled .vtu
  // (cells of 1 cm: no tet straddles x = 2 cm, and every boundary triangle's
  // centroid lies strictly on one side). VTK reads the series' `label`
  // arrays, and the script compares each cell's value with its side.
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "vtk_series" / "labels";
  fs::remove_all(dir);
  fs::create_directories(dir);
  for (const bool surface : {false, true}) {
    nlohmann::json extra = nlohmann::json::parse(R"({"time": {"duration": 0.01}, "outputs": {"vtk": {}}})");
    extra["outputs"]["vtk"]["surface_only"] = surface;
    const fs::path scene = scenario_in(dir, extra);
    TetMesh box = read_tet_mesh(dir / "box.vtu");
    box.labels.clear();
    for (const Tet& t : box.tets) {
      const double x = (box.points[t[0]] + box.points[t[1]] + box.points[t[2]] + box.points[t[3]]).x() / 4;
      box.labels.push_back(x < 0.02 ? 1 : 2);
    }
    write_tet_mesh(dir / "box.vtu", box);
    const fs::path outdir = dir / (surface ? "surface" : "tets");
    const auto run = run_organsim("run " + scene.string() + " -o " + outdir.string(), dir);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const std::string out = testing::run_vtk_python(std::string(R"(
import xml.etree.ElementTree as ET
folder = ')") + outdir.filename().string() + R"('
files = [ds.get('file') for ds in ET.parse(folder + '/states.pvd').getroot().iter('DataSet')]
surface = files[-1].endswith('.vtp')
r = vtk.vtkXMLPolyDataReader() if surface else vtk.vtkXMLUnstructuredGridReader()
r.SetFileName(folder + '/' + files[-1]); r.Update(); g = r.GetOutput()
label = g.GetCellData().GetArray('label')
wrong = 0; count = {1: 0, 2: 0}
for c in range(g.GetNumberOfCells()):
    cell = g.GetCell(c); n = cell.GetNumberOfPoints()
    # The rest position: the current point minus its displacement.
    disp = g.GetPointData().GetArray('displacement')
    x = sum(g.GetPoint(cell.GetPointId(k))[0] - disp.GetTuple3(cell.GetPointId(k))[0] for k in range(n)) / n
    value = int(label.GetValue(c)); count[value] = count.get(value, 0) + 1
    wrong += value != (1 if x < 0.02 else 2)
print(int(surface), label.GetDataTypeAsString(), g.GetNumberOfCells(), count[1], count[2], wrong)
)", dir);
    std::istringstream in(out);
    int is_surface = -1;
    std::string type;
    size_t cells = 0, label_1 = 0, label_2 = 0, wrong = 1;
    in >> is_surface >> type >> cells >> label_1 >> label_2 >> wrong;
    EXPECT_EQ(is_surface, surface ? 1 : 0) << out;
    EXPECT_EQ(type, "int") << out;
    // 4 x 4 x 2 cubes of 6 tets, half on each side; the surface: 64 squares
    // of 2 triangles, the two halves mirror images.
    EXPECT_EQ(cells, surface ? 128u : 192u) << out;
    EXPECT_EQ(label_1, cells / 2) << out;
    EXPECT_EQ(label_2, cells / 2) << out;
    EXPECT_EQ(wrong, 0u) << out;
  }
}

}  // namespace
}  // namespace vtk_series_test
}  // namespace organsim
