// The client's frame: units, the registration matrix and its file, the scene box.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/live/client_frame.h"
#include "core/util/error.h"

namespace organsim {
namespace client_frame_test {
namespace {

namespace fs = std::filesystem;

fs::path write(const std::string& name, const std::string& text) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "client_frame";
  fs::create_directories(dir);
  std::ofstream(dir / name) << text;
  return dir / name;
}

TEST(ClientFrame, MapsAPoseInMillimetresThroughTheRegistrationAndForcesAndStiffnessBack) {
  ClientFrame f;
  f.metres_per_unit = client_unit_metres("mm");
  // 90 degrees about z, then 100 mm along x (client units).
  f.to_scene = read_client_transform(write("rz.json", R"({"matrix": [[0,-1,0,100],[1,0,0,0],[0,0,1,0],[0,0,0,1]]})"));
  const std::array<double, 16> pose{1, 0, 0, 10, 0, 1, 0, 20, 0, 0, 1, 30, 0, 0, 0, 1};
  const Vec3 p = f.scene_position(pose);
  EXPECT_DOUBLE_EQ(p.x(), 0.080);  // (100 - 20) mm
  EXPECT_DOUBLE_EQ(p.y(), 0.010);
  EXPECT_DOUBLE_EQ(p.z(), 0.030);
  // A scene force along +y is the client's +x.
  const Vec3 c = f.client_direction(Vec3(0, 2, 0));
  EXPECT_DOUBLE_EQ(c.x(), 2);
  EXPECT_DOUBLE_EQ(c.y(), 0);
  // A stiffness maps client displacements to client forces as the scene's
  // does scene ones: a scene stiffness along y alone (client x) is the
  // client's xx entry, in N/m whatever the client's length unit.
  Eigen::Matrix3d k = Eigen::Matrix3d::Zero();
  k(1, 1) = -300;
  k(1, 2) = 40;  // scene force along y from a move along z
  const Eigen::Matrix3d kc = f.client_matrix(k);
  Eigen::Matrix3d expected = Eigen::Matrix3d::Zero();
  expected(0, 0) = -300;
  expected(0, 2) = 40;
  EXPECT_EQ(kc, expected);
  const Vec3 move_client(0.001, 0, 0.002);
  EXPECT_LT((f.client_direction(k * f.to_scene.topLeftCorner<3, 3>() * move_client) - kc * move_client).norm(), 1e-15);
  EXPECT_EQ(client_unit_metres("m"), 1.0);
  EXPECT_THROW(client_unit_metres("cm"), Error);
}

TEST(ClientFrame, RefusesATransformFileThatIsNotARigidMatrixNamingTheFile) {
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"notjson.json", "[[1,0,0,0],"},
      {"three.json", "[[1,0,0],[0,1,0],[0,0,1]]"},
      {"scaled.json", "[[2,0,0,0],[0,2,0,0],[0,0,2,0],[0,0,0,1]]"},
      {"mirror.json", "[[-1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]"},
      {"lastrow.json", "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,1,1]]"},
      {"text.json", R"({"matrix": "identity"})"},
      // Entries whose products overflow (R^T R holds inf and NaN).
      {"overflow.json", "[[1e200,1e200,0,0],[-1e200,1e200,0,0],[0,0,1,0],[0,0,0,1]]"},
      {"overflow_diag.json", "[[1e200,0,0,0],[0,1e200,0,0],[0,0,1e200,0],[0,0,0,1]]"},
  };
  for (const auto& [name, text] : bad) {
    const fs::path file = write(name, text);
    try {
      read_client_transform(file);
      ADD_FAILURE() << name << " was accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input) << name;
      EXPECT_EQ(std::string(e.what()).rfind(file.string() + ": ", 0), 0u) << e.what();
    }
  }
}

TEST(ClientFrame, TheSceneBoxIsTheModelsBoxGrownByItsLargestExtent) {
  const SceneBox b = scene_box({Vec3(0, 0, 0), Vec3(0.1, 0.02, 0.05)});
  EXPECT_TRUE(b.contains(Vec3(-0.099, 0.119, 0.149)));
  EXPECT_FALSE(b.contains(Vec3(0.201, 0, 0)));
  EXPECT_FALSE(b.contains(Vec3(0, 0, std::nan(""))));
}

}  // namespace
}  // namespace client_frame_test
}  // namespace organsim
