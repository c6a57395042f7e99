#pragma once
// The OpenIGTLink side of `organsim serve`: a TCP server (POSIX sockets,
// non-blocking, one thread: the run loop's) that reads TRANSFORM messages (and STRING commands)
// from any number of clients through IgtlStream and answers every tick with a
// SENSOR message packed by the library: device "ToolReaction", fifteen
// float64 values fx, fy, fz (N), tx, ty, tz (N m, about the tool centre) and
// the contact stiffness dF/dc row by row (N/m), all in the client's axes,
// timestamp = the tick's simulated end time. A reply that does
// not fit the socket's send buffer at once is dropped and counted (at most
// the tail of one partly sent message waits per client), so a client that
// never reads cannot stall the loop. With --surface-rate, POLYDATA
// "OrganSurface" carries the boundary surface now and then. docs/live.md.
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "core/live/live_link.h"
#include "core/live/refusal_log.h"
#include "igtl/igtl_stream.h"

namespace organsim {

class IgtlServer : public LiveLink {
 public:
  // Listens on bind_address:port (port 0: any free port, see port()).
  // Error(Usage) when the address cannot be used. `send_buffer` is each
  // client's socket send buffer in bytes (Linux doubles it): small for
  // force replies alone, room for a surface message or two with one.
  static constexpr int kRepliesSendBuffer = 8 * 1024;
  IgtlServer(const std::string& bind_address, int port, std::ostream* log, int send_buffer = kRepliesSendBuffer);
  ~IgtlServer() override;
  IgtlServer(const IgtlServer&) = delete;
  IgtlServer& operator=(const IgtlServer&) = delete;

  int port() const { return port_; }

  bool wait_for_client(const std::atomic<bool>& stop) override;
  void receive_until(LiveClock::time_point deadline, LivePoseSink& sink) override;
  void send_reaction(int64_t tick, double t, const Vec3& force, const Vec3& torque,
                     const Eigen::Matrix3d& stiffness) override;
  void send_surface(double t, const std::vector<Vec3>& points, const std::vector<Tri>& triangles) override;
  void send_notice(const std::string& text) override;
  nlohmann::json report() const override;

 private:
  struct Client {
    int fd = -1;
    std::string address;
    IgtlStream stream;
    LiveClock::time_point last_receipt{};
    std::vector<uint8_t> unsent;  // the tail of a partly sent message
  };
  void accept_clients();
  // Reads what the socket holds; false when the client is gone.
  bool read_client(Client& c);
  // Hands all the client's complete messages to the sink; true when it asked to return.
  bool deliver(Client& c, LivePoseSink& sink);
  void close_client(size_t index, const std::string& why);
  // Sends a packed message to every client without blocking; returns how
  // many dropped it and adds to `sent` how many took it.
  int64_t send_all(const uint8_t* data, size_t size, int64_t* sent);

  int listen_fd_ = -1;
  int port_ = 0;
  int send_buffer_;
  std::ostream* log_;
  RefusalLog refusals_;
  std::vector<std::unique_ptr<Client>> clients_;
  std::vector<std::string> seen_;  // every client address, in order of connection
  int64_t replies_sent_ = 0, replies_dropped_ = 0, closed_malformed_ = 0;
  int64_t surfaces_sent_ = 0, surfaces_dropped_ = 0;
  std::vector<uint8_t> reply_;
};

}  // namespace organsim
