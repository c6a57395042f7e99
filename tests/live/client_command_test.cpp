// The live client's text commands (core/live/client_command.h): what is a
// command, what is refused, and what a refusal may print.
#include <gtest/gtest.h>

#include "core/live/client_command.h"

namespace organsim {
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

}  // namespace
}  // namespace organsim
