#include "igtl/igtl_server.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>

#include "core/util/error.h"
#include "igtlPolyDataMessage.h"
#include "igtlSensorMessage.h"
#include "igtlStatusMessage.h"
#include "igtl_util.h"

namespace organsim {

namespace {

void set_non_blocking(int fd) { fcntl(fd, F_SETFL, fcntl(fd, F_GETFL, 0) | O_NONBLOCK); }

std::string address_of(const sockaddr_in& a) {
  char text[INET_ADDRSTRLEN] = {};
  inet_ntop(AF_INET, &a.sin_addr, text, sizeof text);
  return std::string(text) + ":" + std::to_string(ntohs(a.sin_port));
}

void set_time(igtl::MessageBase& m, double t) {
  const double whole = std::floor(t);
  m.SetTimeStamp(static_cast<unsigned int>(whole),
                 igtl_nanosec_to_frac(static_cast<igtl_uint32>(std::llround((t - whole) * 1e9) % 1000000000)));
}

std::vector<uint8_t> packed(igtl::MessageBase& m) {
  m.Pack();
  const auto* p = static_cast<const uint8_t*>(m.GetPackPointer());
  return std::vector<uint8_t>(p, p + m.GetPackSize());
}

}  // namespace

IgtlServer::IgtlServer(const std::string& bind_address, int port, std::ostream* log, int send_buffer)
    : send_buffer_(send_buffer), log_(log), refusals_(log) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<uint16_t>(port));
  if (port < 0 || port > 65535 || inet_pton(AF_INET, bind_address.c_str(), &a.sin_addr) != 1)
    throw Error(ErrorKind::Usage, "--bind/--port: expected an IPv4 address and a port 0-65535 (got " + bind_address +
                                      ":" + std::to_string(port) + ")");
  listen_fd_ = socket(AF_INET, SOCK_STREAM, 0);
  const int one = 1;
  setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  if (listen_fd_ < 0 || bind(listen_fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || listen(listen_fd_, 8) != 0) {
    const std::string why = std::strerror(errno);
    if (listen_fd_ >= 0) close(listen_fd_);
    throw Error(ErrorKind::Usage, "cannot listen on " + bind_address + ":" + std::to_string(port) + ": " + why);
  }
  set_non_blocking(listen_fd_);
  socklen_t len = sizeof a;
  getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&a), &len);
  port_ = ntohs(a.sin_port);
}

IgtlServer::~IgtlServer() {
  for (auto& c : clients_) close(c->fd);
  if (listen_fd_ >= 0) close(listen_fd_);
}

void IgtlServer::accept_clients() {
  for (;;) {
    sockaddr_in a{};
    socklen_t len = sizeof a;
    const int fd = accept(listen_fd_, reinterpret_cast<sockaddr*>(&a), &len);
    if (fd < 0) return;
    set_non_blocking(fd);
    const int one = 1;
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);  // a reply per tick, not per 40 ms
    // A small fixed send buffer (Linux doubles it: 16 KiB by default, ~150
    // replies) instead of one that grows to megabytes: a slow reader then
    // gets recent forces, not seconds of backlog, and the rest is dropped.
    setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &send_buffer_, sizeof send_buffer_);
    auto c = std::make_unique<Client>();
    c->fd = fd;
    c->address = address_of(a);
    if (log_) *log_ << "organsim serve: client " << c->address << " connected\n";
    seen_.push_back(c->address);
    clients_.push_back(std::move(c));
  }
}

bool IgtlServer::wait_for_client(const std::atomic<bool>& stop) {
  while (clients_.empty()) {
    if (stop.load()) return false;
    pollfd p{listen_fd_, POLLIN, 0};
    poll(&p, 1, 100);  // checks `stop` ten times a second
    accept_clients();
  }
  return true;
}

bool IgtlServer::read_client(Client& c) {
  uint8_t buf[65536];
  for (;;) {
    const ssize_t n = recv(c.fd, buf, sizeof buf, MSG_DONTWAIT);
    if (n > 0) {
      c.last_receipt = LiveClock::now();
      c.stream.append(buf, static_cast<size_t>(n));
      if (static_cast<size_t>(n) < sizeof buf) return true;
      continue;
    }
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return true;
    if (n < 0 && errno == EINTR) return true;
    return false;  // closed or failed
  }
}

bool IgtlServer::deliver(Client& c, LivePoseSink& sink) {
  bool asked = false;
  while (auto m = c.stream.next()) {
    if (!m->refused_kind.empty()) {
      refusals_.refuse(m->refused_kind, c.address, m->refused + " (device \"" + m->device + "\")");
      continue;
    }
    if (m->text) {
      sink.on_text({m->device, m->content, c.address, c.last_receipt});
      continue;
    }
    ClientPose pose;
    pose.device = m->device;
    pose.matrix = m->matrix;
    pose.client = c.address;
    pose.received = c.last_receipt;
    asked = sink.on_pose(pose) || asked;
  }
  return asked;
}

void IgtlServer::close_client(size_t index, const std::string& why) {
  if (log_) *log_ << "organsim serve: client " << clients_[index]->address << " " << why << "; the tool holds its last pose\n";
  close(clients_[index]->fd);
  clients_.erase(clients_.begin() + static_cast<std::ptrdiff_t>(index));
}

void IgtlServer::receive_until(LiveClock::time_point deadline, LivePoseSink& sink) {
  // Everything that has arrived is read and handed over, never only the
  // first pose: a session behind the clock must apply the newest pose, not
  // work through a backlog. Only the wait for more stops early when the
  // sink asks.
  bool asked = false;
  for (;;) {
    const auto now = LiveClock::now();
    const bool last_pass = asked || now >= deadline;
    std::vector<pollfd> fds;
    fds.push_back({listen_fd_, POLLIN, 0});
    for (auto& c : clients_) fds.push_back({c->fd, POLLIN, 0});
    const auto wait = last_pass ? LiveClock::duration::zero() : deadline - now;
    const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(wait).count();
    const timespec timeout{static_cast<time_t>(ns / 1000000000), static_cast<long>(ns % 1000000000)};
    const int ready = ppoll(fds.data(), fds.size(), &timeout, nullptr);
    if (ready < 0) return;  // EINTR: SIGINT; the session looks at its stop flag
    if (fds[0].revents) accept_clients();
    for (size_t i = fds.size() - 1; i >= 1; --i) {
      if (!fds[i].revents) continue;
      Client& c = *clients_[i - 1];
      const bool open = read_client(c);
      asked = deliver(c, sink) || asked;
      if (c.stream.broken()) {
        ++closed_malformed_;
        refusals_.refuse("malformed_header", c.address, c.stream.broken_reason());
        close_client(i - 1, "closed after a malformed header");
      } else if (!open) {
        close_client(i - 1, "disconnected");
      }
    }
    // One pass without waiting once the deadline has passed or the sink
    // asked: what arrives later belongs to the next tick.
    if (last_pass) return;
  }
}

int64_t IgtlServer::send_all(const uint8_t* data, size_t size, int64_t* sent) {
  int64_t dropped = 0;
  for (size_t i = clients_.size(); i-- > 0;) {
    Client& c = *clients_[i];
    if (!c.unsent.empty()) {
      const ssize_t n = send(c.fd, c.unsent.data(), c.unsent.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
      if (n > 0) c.unsent.erase(c.unsent.begin(), c.unsent.begin() + n);
      if (!c.unsent.empty()) {
        ++dropped;
        continue;
      }
    }
    const ssize_t n = send(c.fd, data, size, MSG_DONTWAIT | MSG_NOSIGNAL);
    if (n >= 0) {
      if (sent) ++*sent;
      // A message is never cut: the tail of a partly sent one goes first next time.
      if (n < static_cast<ssize_t>(size)) c.unsent.assign(data + n, data + size);
      continue;
    }
    if (errno == EAGAIN || errno == EWOULDBLOCK) {
      ++dropped;
      continue;
    }
    close_client(i, std::string("could not be written to (") + std::strerror(errno) + ")");
  }
  return dropped;
}

void IgtlServer::send_reaction(int64_t /*tick*/, double t, const Vec3& force, const Vec3& torque,
                               const Eigen::Matrix3d& stiffness) {
  if (clients_.empty()) return;
  igtl::SensorMessage::Pointer m = igtl::SensorMessage::New();
  m->SetDeviceName("ToolReaction");
  m->SetLength(15);
  for (unsigned i = 0; i < 3; ++i) {
    m->SetValue(i, force[i]);
    m->SetValue(i + 3, torque[i]);
    for (unsigned j = 0; j < 3; ++j) m->SetValue(6 + 3 * i + j, stiffness(i, j));  // row by row
  }
  set_time(*m, t);
  reply_ = packed(*m);
  replies_dropped_ += send_all(reply_.data(), reply_.size(), &replies_sent_);
}

void IgtlServer::send_surface(double t, const std::vector<Vec3>& points, const std::vector<Tri>& triangles) {
  if (clients_.empty()) return;
  igtl::PolyDataPointArray::Pointer p = igtl::PolyDataPointArray::New();
  p->SetNumberOfPoints(static_cast<int>(points.size()));
  for (size_t i = 0; i < points.size(); ++i)
    p->SetPoint(static_cast<unsigned>(i), static_cast<igtlFloat32>(points[i].x()), static_cast<igtlFloat32>(points[i].y()),
                static_cast<igtlFloat32>(points[i].z()));
  igtl::PolyDataCellArray::Pointer cells = igtl::PolyDataCellArray::New();
  for (const Tri& f : triangles) {
    igtlUint32 ids[3] = {static_cast<igtlUint32>(f[0]), static_cast<igtlUint32>(f[1]), static_cast<igtlUint32>(f[2])};
    cells->AddCell(3, ids);
  }
  igtl::PolyDataMessage::Pointer m = igtl::PolyDataMessage::New();
  m->SetDeviceName("OrganSurface");
  m->SetPoints(p);
  m->SetPolygons(cells);
  set_time(*m, t);
  const std::vector<uint8_t> bytes = packed(*m);
  // Only to a client whose replies have all gone out: a surface never
  // delays a force reply by more than what the socket takes at once.
  for (auto& c : clients_) {
    if (!c->unsent.empty()) {
      ++surfaces_dropped_;
      continue;
    }
    const ssize_t n = send(c->fd, bytes.data(), bytes.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
    if (n < 0) {
      ++surfaces_dropped_;
      continue;
    }
    ++surfaces_sent_;
    if (n < static_cast<ssize_t>(bytes.size())) c->unsent.assign(bytes.begin() + n, bytes.end());
  }
}

void IgtlServer::send_notice(const std::string& text) {
  igtl::StatusMessage::Pointer m = igtl::StatusMessage::New();
  m->SetDeviceName("organsim");
  m->SetCode(igtl::StatusMessage::STATUS_PANICK_MODE);
  m->SetErrorName("stopped");
  m->SetStatusString(text.c_str());
  const std::vector<uint8_t> bytes = packed(*m);
  send_all(bytes.data(), bytes.size(), nullptr);
}

nlohmann::json IgtlServer::report() const {
  return {{"protocol", "OpenIGTLink"},
          {"port", port_},
          {"clients", seen_},
          {"replies_sent", replies_sent_},
          {"replies_dropped", replies_dropped_},
          {"surfaces_sent", surfaces_sent_},
          {"surfaces_dropped", surfaces_dropped_},
          {"connections_closed_for_malformed_headers", closed_malformed_},
          {"refused", refusals_.counts()}};
}

}  // namespace organsim
