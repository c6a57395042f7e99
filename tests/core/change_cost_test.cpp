// The bench's "one topology change" (core/topology/change_cost.h): at every
// mesh size its blade cuts a comparable local patch, so the rows compare the
// cost of the same kind of change, and the check it times never exceeds the
// full dt_crit. (Its times are results for `organsim bench`, not asserted.)
#include <gtest/gtest.h>

#include "core/topology/change_cost.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace change_cost_test {
namespace {

TEST(ChangeCost, EverySizeCutsAComparableLocalPatch) {
  Material material;
  material.density = 1000;
  material.young_modulus = 5000;
  material.volume_modulus = 2000;
  std::vector<ChangeCost> costs;
  for (int n : {6, 12}) {
    const Model model = build_model(testing::jittered_box(n, 1.0, 0.2, 5), material, {});
    costs.push_back(measure_change_cost(model, 1));
    const ChangeCost& c = costs.back();
    EXPECT_GT(c.faces_separated, 4) << n;
    EXPECT_GT(c.points_added, 0) << n;
    // A local cut: a small share of the model's faces.
    EXPECT_LT(c.faces_separated, 0.1 * 5 * model.ntet()) << n;
    EXPECT_GT(c.guaranteed_over_dt_crit, 0) << n;
    EXPECT_LE(c.guaranteed_over_dt_crit, 1) << n;
  }
  // Sized by the spring length, not the model: 8x the tets, about as many
  // faces (a blade sized by the model cuts 4x as many on the finer mesh).
  EXPECT_LT(costs[1].faces_separated, 3 * costs[0].faces_separated);
  EXPECT_LT(costs[0].faces_separated, 3 * costs[1].faces_separated);
}

}  // namespace
}  // namespace change_cost_test
}  // namespace organsim
