// The live client's text commands (core/live/client_command.h): what is a
// command, what is refused, and what a refusal may print.
#include <gtest/gtest.h>

#include "core/live/client_command.h"

namespace organsim {
namespace client_command_test {
namespace {

TEST(ClientCommand, CutTakesNoLengthsOrTwoPositiveOnesAndNothingElseIsACommand) {
  const ParsedCommand plain = parse_client_command("  cut\n");
  ASSERT_TRUE(std::holds_alternative<CutCommand>(plain));
  EXPECT_FALSE(std::get<CutCommand>(plain).depth);
  const ParsedCommand sized = parse_client_command("CUT 12.5 3");
  ASSERT_TRUE(std::holds_alternative<CutCommand>(sized));
  EXPECT_EQ(*std::get<CutCommand>(sized).depth, 12.5);
  EXPECT_EQ(*std::get<CutCommand>(sized).width, 3);
  for (const char* text : {"", "   ", "CUTS", "SLICE", "CUT 5", "CUT 5 0", "CUT 5 -2", "CUT 5 nan", "CUT 5 inf",
                           "CUT 5 10mm", "CUT 1 2 3", "CUT\x01"}) {
    const ParsedCommand p = parse_client_command(text);
    ASSERT_TRUE(std::holds_alternative<std::string>(p)) << "accepted \"" << text << "\"";
    EXPECT_FALSE(std::get<std::string>(p).empty());
  }
}

TEST(ClientCommand, RefusalsPrintOnlyPrintableTextAndNotMuchOfIt) {
  EXPECT_EQ(printable_text(std::string("a\0b\n\xff", 5)), "a\\x00b\\x0a\\xff");
  EXPECT_EQ(printable_text(std::string(100, 'x'), 10), std::string(10, 'x') + "...");
  const std::string why = std::get<std::string>(parse_client_command(std::string(1000, '\x07')));
  EXPECT_LT(why.size(), 300u);
  EXPECT_EQ(why.find('\x07'), std::string::npos);
}

// The blade follows the pose's axes through the registration: a pose turned
// 90 degrees about x (its z axis along the client's -y) in a client frame
// turned 90 degrees about z (client -y is scene +x), in mm.
TEST(ClientCommand, TheBladeRunsAlongThePosesZAxisAndSweepsAlongItsXAxisInTheScene) {
  ClientFrame frame;
  frame.to_scene << 0, -1, 0, 100,  //
      1, 0, 0, 0,                   //
      0, 0, 1, 0,                   //
      0, 0, 0, 1;
  const std::array<double, 16> pose{1, 0, 0, 10, 0, 0, -1, 20, 0, 1, 0, 30, 0, 0, 0, 1};
  CutCommand sized;
  sized.depth = 15;
  sized.width = 8;
  const CutBlade b = cut_blade(frame, pose, sized);
  // Centre: client (10, 20, 30) mm -> scene (100 - 20, 10, 30) mm. Axis z
  // (client (0, -1, 0)) -> scene (1, 0, 0); sweep x (client (1, 0, 0)) -> scene (0, 1, 0).
  const double tol = 1e-15;
  EXPECT_LT((b.a0 - Vec3(0.080, 0.006, 0.030)).norm(), tol);
  EXPECT_LT((b.b0 - Vec3(0.095, 0.006, 0.030)).norm(), tol);
  EXPECT_LT((b.a1 - Vec3(0.080, 0.014, 0.030)).norm(), tol);
  EXPECT_LT((b.b1 - Vec3(0.095, 0.014, 0.030)).norm(), tol);
  // Without lengths: the defaults, in metres whatever the client's unit.
  const CutBlade d = cut_blade(frame, pose, CutCommand{});
  EXPECT_NEAR((d.b0 - d.a0).norm(), CutCommand::kDefaultDepth, tol);
  EXPECT_NEAR((d.a1 - d.a0).norm(), CutCommand::kDefaultWidth, tol);
}

}  // namespace
}  // namespace client_command_test
}  // namespace organsim
