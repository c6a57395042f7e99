// IgtlServer in-process on loopback: what one receive hands to the session.
#include <gtest/gtest.h>

#include <thread>

#include "core/util/error.h"
#include "igtl/igtl_server.h"
#include "tests/live/igtl_test_client.h"

namespace organsim {
namespace igtl_server_test {
namespace {

struct CountingSink : LivePoseSink {
  std::vector<ClientPose> poses;
  std::vector<ClientText> texts;
  size_t poses_before_text = 0;
  bool on_pose(const ClientPose& p) override {
    poses.push_back(p);
    return true;  // as the session does once its tick may start
  }
  void on_text(const ClientText& t) override {
    texts.push_back(t);
    poses_before_text = poses.size();
  }
};

// A session behind the clock must get the newest pose, so one receive takes
// every pose that has arrived even though the sink asks to return at the
// first; a command comes in its place among them.
TEST(IgtlServer, OneReceiveHandsOverEveryPoseAndCommandThatHasArrivedInOrder) {
  IgtlServer server("127.0.0.1", 0, nullptr);
  test::IgtlTestClient client;
  ASSERT_TRUE(client.connect_to(server.port()));
  const std::atomic<bool> stop{false};
  ASSERT_TRUE(server.wait_for_client(stop));
  for (float z : {50.0f, 49.0f, 48.0f}) {
    ASSERT_TRUE(client.send_pose("Tool", {20, 20, z}));
    if (z == 49.0f) {
      ASSERT_TRUE(client.send_text("Command", "CUT"));
    }
  }
  ASSERT_TRUE(client.wait_until_received());  // all of them in the server's socket
  CountingSink sink;
  server.receive_until(LiveClock::now() - std::chrono::seconds(1), sink);
  ASSERT_EQ(sink.poses.size(), 3u);
  EXPECT_EQ(sink.poses.back().matrix[11], 48.0);
  EXPECT_EQ(sink.poses.back().device, "Tool");
  EXPECT_EQ(sink.poses.back().client.rfind("127.0.0.1:", 0), 0u);
  ASSERT_EQ(sink.texts.size(), 1u);
  EXPECT_EQ(sink.texts[0].text, "CUT");
  EXPECT_EQ(sink.texts[0].device, "Command");
  EXPECT_EQ(sink.texts[0].client, sink.poses.back().client);
  EXPECT_EQ(sink.poses_before_text, 2u);
}

TEST(IgtlServer, RefusesAnAddressItCannotUse) {
  EXPECT_THROW(IgtlServer("not-an-address", 0, nullptr), Error);
}

}  // namespace
}  // namespace igtl_server_test
}  // namespace organsim
