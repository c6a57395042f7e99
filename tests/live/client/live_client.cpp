// organsim_live_client: an OpenIGTLink client for `organsim serve` that
// streams a straight path of TRANSFORM poses at a fixed rate and reads every
// reply (the library packs and unpacks). scripts/live_bench.sh drives the
// liver with it; docs/live.md shows it as a first client.
//   organsim_live_client PORT RATE_HZ SECONDS X0,Y0,Z0 X1,Y1,Z1 [DEVICE] [--down] [--cut K [--cut-text TEXT]]
// Positions in mm; the tool moves from the first to the second over the
// first half of SECONDS and holds there. --down turns the tool's z axis (the
// instrument's, docs/live.md#commands) to -z instead of +z; --cut K sends
// the STRING command CUT (or TEXT) right after the K-th pose (from 0). Prints the
// replies received and the last force.
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "tests/live/igtl_test_client.h"

namespace {

bool parse_point(const char* text, std::array<float, 3>& p) {
  return std::sscanf(text, "%f,%f,%f", &p[0], &p[1], &p[2]) == 3;
}

}  // namespace

int main(int argc, char** argv) {
  std::array<float, 3> from{}, to{};
  std::string device = "Tool";
  bool down = false;
  long cut_at = -1;
  std::string cut_text = "CUT";
  bool usage = argc < 6 || !parse_point(argv[4], from) || !parse_point(argv[5], to);
  for (int i = 6; !usage && i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--down") {
      down = true;
    } else if (a == "--cut" && i + 1 < argc) {
      cut_at = std::atol(argv[++i]);
    } else if (a == "--cut-text" && i + 1 < argc) {
      cut_text = argv[++i];
    } else if (a.rfind("--", 0) != 0) {
      device = a;
    } else {
      usage = true;
    }
  }
  if (usage) {
    std::fprintf(stderr, "usage: %s PORT RATE_HZ SECONDS X0,Y0,Z0 X1,Y1,Z1 [DEVICE] [--down] [--cut K [--cut-text TEXT]]  (positions in mm)\n",
                 argv[0]);
    return 2;
  }
  const int port = std::atoi(argv[1]);
  const double rate = std::atof(argv[2]), seconds = std::atof(argv[3]);
  const float z_axis = down ? -1.0f : 1.0f;  // a rotation of 180 degrees about x when down
  organsim::test::IgtlTestClient client;
  if (!client.connect_to(port)) {
    std::fprintf(stderr, "cannot connect to 127.0.0.1:%d\n", port);
    return 1;
  }
  const long n = static_cast<long>(rate * seconds);
  // Room for every reply up front: a vector doubling mid-stream copies all
  // it holds (megabytes after 16k replies), and on a machine the server
  // shares that stalls one of its ticks.
  client.replies.reserve(static_cast<size_t>(n) + 1024);
  const auto start = std::chrono::steady_clock::now();
  for (long k = 0; k < n; ++k) {
    std::this_thread::sleep_until(start + std::chrono::duration<double>(static_cast<double>(k) / rate));
    const float s = std::min(1.0f, 2.0f * static_cast<float>(k) / static_cast<float>(n));
    const std::array<float, 3> p{from[0] + s * (to[0] - from[0]), from[1] + s * (to[1] - from[1]),
                                 from[2] + s * (to[2] - from[2])};
    igtl::Matrix4x4 m = {{1, 0, 0, p[0]}, {0, z_axis, 0, p[1]}, {0, 0, z_axis, p[2]}, {0, 0, 0, 1}};
    if (!client.send_bytes(organsim::test::IgtlTestClient::transform(device, m)) || !client.read_replies(0)) break;
    if (k == cut_at && !client.send_text("Command", cut_text)) break;
  }
  client.read_until_closed(5);
  std::printf("replies: %zu", client.replies.size());
  if (!client.replies.empty()) {
    const auto& r = client.replies.back();
    std::printf(", last at t = %.3f s: force %.6g %.6g %.6g N", r.t, r.values[0], r.values[1], r.values[2]);
  }
  std::printf("\n");
  return client.bad_crc == 0 ? 0 : 1;
}
