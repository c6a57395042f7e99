// A topology change's backend work split in two (Backend::prepare off the
// tick's path, Backend::adopt on it), as the run loop does for a change its
// worker builds: the tables prepared on another thread while the backend
// ticks the previous version give, once adopted, exactly the run of a
// rebuild at that tick, on the reference backend and on every target and
// precision of the CPU backend's kernel.
#include <gtest/gtest.h>

#include <future>

#include "core/model/model_rebuild.h"
#include "core/sim/cpu_backend.h"
#include "core/sim/cpu_kernel_simd.h"
#include "core/util/error.h"
#include "tests/core/cpu_kernel_test_util.h"

namespace organsim {
namespace prepare_adopt_test {
namespace {

using testing::kSize;

struct Trajectory {
  std::vector<Vec3> x;             // positions at the end
  std::vector<Reaction> reaction;  // per tick
};

// A box pushed from above for 10 ticks, cut through at x = 0.025, pushed 10
// ticks more into the cut's top edge. `prepare_early`: the cut's tables are
// prepared on another thread while the first 10 ticks run and adopted after
// them; else rebuild() at the tick.
Trajectory cut_run(const Model& model, const Model& cut, const testing::Stepper& stepper, bool prepare_early) {
  const BackendTool tool{true, ToolMode::Push, 0.02, 500};
  auto backend = stepper.make(model, tool);
  std::future<std::unique_ptr<PreparedModel>> prepared;
  if (prepare_early) prepared = std::async(std::launch::async, [&] { return backend->prepare(cut); });
  TickRequest request;
  request.dt = 5e-5;
  request.substeps = 20;
  request.tool_active = true;
  request.tool_from = request.tool_to = Vec3(0.025, 0.025, kSize + 0.01);
  Trajectory out;
  for (int i = 0; i < 10; ++i) out.reaction.push_back(backend->tick(request));
  if (prepare_early) {
    backend->adopt(prepared.get());
  } else {
    backend->rebuild(cut);
  }
  request.tool_to = Vec3(0.025, 0.025, kSize - 0.01);
  for (int i = 0; i < 10; ++i) out.reaction.push_back(backend->tick(request));
  backend->positions(out.x);
  return out;
}

TEST(PrepareAdopt, TablesPreparedWhileTickingAdoptExactlyAsARebuildAtTheTick) {
  std::vector<testing::Stepper> steppers = {testing::kReference};
  for (const SimdTarget& target : simd_targets_supported()) {
    steppers.push_back(testing::fast_kernel(target.name, Precision::Double));
    steppers.push_back(testing::fast_kernel(target.name, Precision::Float));
  }
  for (testing::VolumeTerm volume : testing::kEveryTerm) {
    // No jitter, so that x = 0.025 (between cells 1 and 2) is a plane of tet faces.
    const Model model = testing::random_model(4, 4, volume, true, kDefaultChunkSize, 0);
    const Model cut = rebuild_model(model, testing::split_across_plane_x(model, 0.025));
    ASSERT_GT(cut.npoint(), model.npoint());
    for (const testing::Stepper& stepper : steppers) {
      SCOPED_TRACE(std::string(testing::volume_term_name(volume)) + ", " + stepper.label() +
                   (stepper.cpu && stepper.cpu->precision == Precision::Float ? ", float" : ", double"));
      const Trajectory rebuilt = cut_run(model, cut, stepper, false);
      const Trajectory adopted = cut_run(model, cut, stepper, true);
      // The same arithmetic on the same state: nothing may differ in any bit.
      ASSERT_EQ(rebuilt.x.size(), static_cast<size_t>(cut.npoint()));
      EXPECT_EQ(adopted.x, rebuilt.x);
      ASSERT_EQ(adopted.reaction.size(), rebuilt.reaction.size());
      double pushed = 0;
      for (size_t i = 0; i < rebuilt.reaction.size(); ++i) {
        EXPECT_EQ(adopted.reaction[i].force, rebuilt.reaction[i].force) << "tick " << i;
        EXPECT_EQ(adopted.reaction[i].torque, rebuilt.reaction[i].torque) << "tick " << i;
        pushed = std::max(pushed, rebuilt.reaction[i].force.norm());
      }
      EXPECT_GT(pushed, 0) << "the tool touched the box";
    }
  }
}

TEST(PrepareAdopt, AVersionPreparedElsewhereIsRefused) {
  const Model model = testing::random_model(4, 2, testing::VolumeTerm::PerTet, false);
  auto backend = make_cpu_backend(model, {}, {Precision::Double, 1});
  auto other = make_cpu_backend(model, {}, {Precision::Float, 1});
  auto reference = testing::kReference.make(model);
  EXPECT_THROW(backend->adopt(other->prepare(model)), Error);
  EXPECT_THROW(backend->adopt(reference->prepare(model)), Error);
  EXPECT_THROW(reference->adopt(backend->prepare(model)), Error);
  EXPECT_THROW(backend->adopt(std::make_unique<PreparedModel>(model)), Error);
}

}  // namespace
}  // namespace prepare_adopt_test
}  // namespace organsim
