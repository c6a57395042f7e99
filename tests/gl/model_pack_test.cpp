// The std430 packing of the Model for the step kernel (no GL needed): every
// spring and tet appears once per end / vertex with the Model's parameters,
// and padding entries are inert (the lane's own point, zero parameters).
#include <gtest/gtest.h>

#include <map>

#include "core/gl/gl_model_pack.h"
#include "core/util/error.h"
#include "gl_test_scenes.h"
#include "shaders/bindings.glsl.h"

namespace organsim::gl {
namespace model_pack_test {
namespace {

TEST(GlModelPack, EveryEntryOnceAtEachEndAndPaddingInert) {
  const Model model = gl_test::box_model(3, 3, 2, true, 1e4, Vec3(0, 0, -9.81));
  const PackedModel p = pack_model(model);
  ASSERT_EQ(p.npad % ORGANSIM_GL_CHUNK, 0);
  ASSERT_GE(p.npad, model.npoint());
  // Springs: count (point, other) pairs; each spring must give (a, b) and (b, a).
  std::map<std::pair<int32_t, int32_t>, int> seen;
  int padding = 0;
  for (int32_t c = 0; c < p.nchunk; ++c) {
    const int32_t offset = p.chunks[4 * c], slots = p.chunks[4 * c + 1];
    for (int32_t j = 0; j < slots; ++j) {
      for (int32_t lane = 0; lane < ORGANSIM_GL_CHUNK; ++lane) {
        const SpringEntry& e = p.springs[offset + j * ORGANSIM_GL_CHUNK + lane];
        const int32_t point = c * ORGANSIM_GL_CHUNK + lane;
        if (e.other == point) {
          EXPECT_EQ(e.k, 0.0f);
          EXPECT_EQ(e.d, 0.0f);
          ++padding;
        } else {
          ++seen[{point, e.other}];
        }
      }
    }
  }
  EXPECT_EQ(seen.size(), 2u * model.nspring());
  for (int32_t s = 0; s < model.nspring(); ++s) {
    const auto [a, b] = model.spring_ends[s];
    EXPECT_EQ((seen[{a, b}]), 1);
    EXPECT_EQ((seen[{b, a}]), 1);
  }
  EXPECT_GT(padding, 0);  // the last chunk is partly padding
  // Tets: 4 entries per tet; padding has k_v = 0.
  int64_t real = 0;
  for (const TetEntry& t : p.tets) real += t.k_v > 0 ? 1 : 0;
  EXPECT_EQ(real, 4 * static_cast<int64_t>(model.ntet()));
  // Padding points never move and never touch the tool (mass 0).
  for (int32_t i = model.npoint(); i < p.npad; ++i) {
    EXPECT_EQ(p.mass[4 * i], 0.0f);
    EXPECT_EQ(p.mass[4 * i + 1], 0.0f);
  }
}

// The smoothed shear element's weights w = k_t / K_p in the entries' 4th
// slot: each point's sum to 1 (so Fbar - I is a weighted mean of its tets'
// F - I), padding entries and points without tets have none, and the
// per-tet formulation packs none at all.
TEST(GlModelPack, SmoothedShearWeightsOfEachPointSumToOne) {
  for (const ShearFormulation formulation : {ShearFormulation::Smoothed, ShearFormulation::PerTet}) {
    const Model model = gl_test::poisson_box(0.0, Vec3::Zero(), Material{}.spring_damping_time, formulation);
    const PackedModel p = pack_model(model);
    const bool smoothed = formulation == ShearFormulation::Smoothed;
    for (int32_t c = 0; c < p.nchunk; ++c) {
      const int32_t offset = p.chunks[4 * c + 2], slots = p.chunks[4 * c + 3];
      for (int32_t lane = 0; lane < ORGANSIM_GL_CHUNK; ++lane) {
        double sum = 0;
        for (int32_t j = 0; j < slots; ++j) {
          const ShearEntry& e = p.shear[offset + j * ORGANSIM_GL_CHUNK + lane];
          if (e.k == 0.0f) {
            EXPECT_EQ(e.w, 0.0f);  // padding
          }
          sum += e.w;
        }
        const int32_t point = c * ORGANSIM_GL_CHUNK + lane;
        EXPECT_NEAR(sum, smoothed && point < model.npoint() ? 1.0 : 0.0, 1e-6) << "point " << point;
      }
    }
  }
}

TEST(GlModelPack, LeanModelHasNoTetEntriesAndWrongChunkSizeIsAnError) {
  const Model lean = gl_test::box_model(2, 2, 2, true, 0, Vec3(0, 0, 0));
  EXPECT_TRUE(pack_model(lean).tets.empty());
  const TetMesh mesh = make_box_tet_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1), 2, 2, 2);
  ModelOptions options;
  options.chunk_size = 32;
  const Model other = build_model(mesh, Material{}, options, "box");
  try {
    pack_model(other);
    ADD_FAILURE() << "chunk size 32 accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Backend);
    EXPECT_NE(std::string(e.what()).find("chunk size is 32"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace model_pack_test
}  // namespace organsim::gl
