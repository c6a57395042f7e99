#pragma once
// What the live session (live_session.h) needs of a network protocol, and
// nothing more: wait for a client, receive tool poses and commands until a deadline, send
// each tick's reaction without blocking. The OpenIGTLink server (igtl/)
// implements it; the session's logic is tested without sockets.
#include <nlohmann/json.hpp>

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <string>

#include <vector>

#include "core/util/vec.h"

namespace organsim {

using LiveClock = std::chrono::steady_clock;

// A pose as the client sent it: the device (tool) name, the row-major 4x4
// matrix in the client's frame and units, who sent it and when it arrived.
struct ClientPose {
  std::string device;
  std::array<double, 16> matrix{};
  std::string client;  // "address:port"
  LiveClock::time_point received;
};

// A STRING message's text (a command, core/live/client_command.h), who sent it and when it arrived.
struct ClientText {
  std::string device;
  std::string text;
  std::string client;  // "address:port"
  LiveClock::time_point received;
};

class LivePoseSink {
 public:
  virtual ~LivePoseSink() = default;
  // Called for every well-formed pose; true asks the link to return from
  // receive_until now (the session starts its tick).
  virtual bool on_pose(const ClientPose& pose) = 0;
  // Called for every well-formed STRING, in order with the poses.
  virtual void on_text(const ClientText& text) = 0;
};

class LiveLink {
 public:
  virtual ~LiveLink() = default;
  // Blocks until a client has connected; false if `stop` became true first.
  virtual bool wait_for_client(const std::atomic<bool>& stop) = 0;
  // Accepts connections and receives messages until `deadline` or until the
  // sink asks to return; when the deadline has passed, takes what is already
  // there without waiting. Malformed or unknown messages are refused and
  // logged here (with the client's address), never passed on.
  virtual void receive_until(LiveClock::time_point deadline, LivePoseSink& sink) = 0;
  // The reaction at the end of tick `tick` (simulated time `t`, s; force N,
  // torque N m, in the client's axes) and the contact's local stiffness
  // dF/dc (N/m, client axes), to every connected client, without blocking:
  // a reply that cannot go out at once is dropped and counted.
  virtual void send_reaction(int64_t tick, double t, const Vec3& force, const Vec3& torque,
                             const Eigen::Matrix3d& stiffness) = 0;
  // The organ's boundary surface at simulated time `t` (points in the
  // client's frame and units, triangles by point index), at display rate,
  // best effort: dropped for a client that has not taken the last replies.
  virtual void send_surface(double t, const std::vector<Vec3>& points, const std::vector<Tri>& triangles) = 0;
  // A last word to the clients (why the session stopped), best effort.
  virtual void send_notice(const std::string& text) = 0;
  // Counters for the force log's meta (connections, refused messages by kind,
  // replies sent and dropped).
  virtual nlohmann::json report() const = 0;
};

}  // namespace organsim
