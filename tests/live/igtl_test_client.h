#pragma once
// The live tests' OpenIGTLink client: a loopback TCP connection whose poses
// are packed and whose replies are unpacked (CRC checked) by the library, so
// our server is read by the library's own code, not by ours.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <linux/sockios.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "igtlMessageHeader.h"
#include "igtl_header.h"
#include "igtl_polydata.h"
#include "igtl_util.h"
#include "igtlSensorMessage.h"
#include "igtlStringMessage.h"
#include "igtlTransformMessage.h"

namespace organsim::test {

struct Reply {
  std::string type, device;
  double t = 0;                  // the header's timestamp, s
  std::array<double, 15> values{};  // SENSOR: fx fy fz tx ty tz, then the stiffness row by row
  unsigned length = 0;              // SENSOR: how many values it carried
  std::vector<std::array<float, 3>> points;  // POLYDATA
  std::vector<std::array<uint32_t, 3>> triangles;  // POLYDATA polygons of three points
};

// A POLYDATA message (header and body) into r.points and r.triangles, with
// the library's C functions: its CRC (crc64 of the body against the
// header's) and igtl_polydata_unpack, whose arrays are freed after the copy.
// igtl::PolyDataMessage::Unpack of Debian's libOpenIGTLink 1.11 never frees
// them: about 44 kB lost per message of 1000 points and 2000 triangles.
inline bool unpack_polydata(const uint8_t* message, size_t body, Reply& r) {
  igtl_header h;
  std::memcpy(&h, message, IGTL_HEADER_SIZE);
  igtl_header_convert_byte_order(&h);
  auto* content = const_cast<unsigned char*>(message + IGTL_HEADER_SIZE);
  if (h.body_size != body || crc64(content, body, 0) != h.crc) return false;
  igtl_polydata_info info;
  igtl_polydata_init_info(&info);
  const bool ok = igtl_polydata_unpack(IGTL_TYPE_PREFIX_NONE, content, &info, body) != 0;
  if (ok) {
    for (igtl_uint32 i = 0; i < info.header.npoints; ++i)
      r.points.push_back({info.points[3 * i], info.points[3 * i + 1], info.points[3 * i + 2]});
    const igtl_uint32* cell = info.polygons;
    for (igtl_uint32 i = 0; i < info.header.npolygons; cell += 1 + *cell, ++i)
      if (*cell == 3) r.triangles.push_back({cell[1], cell[2], cell[3]});
  }
  igtl_polydata_free_info(&info);
  return ok;
}

class IgtlTestClient {
 public:
  // SO_RCVBUF for the next connection (bytes): a client that never reads fills it soon.
  void shrink_receive_buffer(int bytes) { receive_buffer_ = bytes; }

  // Connects to 127.0.0.1:port, retrying for up to `seconds`.
  bool connect_to(int port, double seconds = 30) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < until) {
      fd_ = socket(AF_INET, SOCK_STREAM, 0);
      if (receive_buffer_ > 0) setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &receive_buffer_, sizeof receive_buffer_);
      sockaddr_in a{};
      a.sin_family = AF_INET;
      a.sin_port = htons(static_cast<uint16_t>(port));
      inet_pton(AF_INET, "127.0.0.1", &a.sin_addr);
      if (::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0) {
        const int one = 1;
        setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        return true;
      }
      close(fd_);
      fd_ = -1;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return false;
  }
  ~IgtlTestClient() { disconnect(); }
  void disconnect() {
    if (fd_ >= 0) close(fd_);
    fd_ = -1;
  }

  // A TRANSFORM with identity rotation and translation `p` (client units), packed by the library.
  static std::vector<uint8_t> transform(const std::string& device, const std::array<float, 3>& p) {
    igtl::Matrix4x4 matrix = {{1, 0, 0, p[0]}, {0, 1, 0, p[1]}, {0, 0, 1, p[2]}, {0, 0, 0, 1}};
    return transform(device, matrix);
  }
  // A TRANSFORM with any matrix (client units).
  static std::vector<uint8_t> transform(const std::string& device, igtl::Matrix4x4& matrix) {
    igtl::TransformMessage::Pointer m = igtl::TransformMessage::New();
    m->SetDeviceName(device.c_str());
    m->SetMatrix(matrix);
    m->Pack();
    const auto* b = static_cast<const uint8_t*>(m->GetPackPointer());
    return std::vector<uint8_t>(b, b + m->GetPackSize());
  }

  // A STRING (a command to the server), packed by the library.
  static std::vector<uint8_t> text(const std::string& device, const std::string& content) {
    igtl::StringMessage::Pointer m = igtl::StringMessage::New();
    m->SetDeviceName(device.c_str());
    m->SetString(content.c_str());
    m->Pack();
    const auto* b = static_cast<const uint8_t*>(m->GetPackPointer());
    return std::vector<uint8_t>(b, b + m->GetPackSize());
  }

  bool send_bytes(const std::vector<uint8_t>& bytes) {
    size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t n = send(fd_, bytes.data() + done, bytes.size() - done, MSG_NOSIGNAL);
      if (n <= 0) return false;
      done += static_cast<size_t>(n);
    }
    return true;
  }
  bool send_pose(const std::string& device, const std::array<float, 3>& p) { return send_bytes(transform(device, p)); }
  bool send_text(const std::string& device, const std::string& content) { return send_bytes(text(device, content)); }

  // Waits up to `seconds` until every byte sent is in the server's socket
  // (the kernel's send queue holds only bytes not yet acknowledged, and on
  // loopback the server's side acknowledges what it has queued); false if
  // that did not come.
  bool wait_until_received(double seconds = 60) const {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (true) {
      int unacknowledged = 0;
      if (ioctl(fd_, SIOCOUTQ, &unacknowledged) != 0) return false;
      if (unacknowledged == 0) return true;
      if (std::chrono::steady_clock::now() > until) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }

  // Reads what has arrived (waiting up to `wait_ms`), unpacking complete
  // messages into replies; false once the server has closed the connection.
  bool read_replies(int wait_ms = 0) {
    pollfd p{fd_, POLLIN, 0};
    if (poll(&p, 1, wait_ms) <= 0) return true;
    uint8_t buf[65536];
    const ssize_t n = recv(fd_, buf, sizeof buf, MSG_DONTWAIT);
    if (n == 0) return false;
    if (n < 0) return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR;
    bytes_.insert(bytes_.end(), buf, buf + n);
    unpack();
    return true;
  }
  // Reads until the server closes the connection or `seconds` pass.
  void read_until_closed(double seconds) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < until && read_replies(50)) {
    }
  }

  std::vector<Reply> replies;
  int bad_crc = 0;  // replies whose body failed the library's CRC check

 private:
  void unpack() {
    size_t at = 0;
    while (bytes_.size() - at >= IGTL_HEADER_SIZE) {
      igtl::MessageHeader::Pointer h = igtl::MessageHeader::New();
      h->InitPack();
      std::memcpy(h->GetPackPointer(), bytes_.data() + at, IGTL_HEADER_SIZE);
      h->Unpack();
      const size_t body = static_cast<size_t>(h->GetBodySizeToRead());
      if (bytes_.size() - at < IGTL_HEADER_SIZE + body) break;
      Reply r;
      r.type = h->GetDeviceType();
      r.device = h->GetDeviceName();
      igtl::TimeStamp::Pointer ts = igtl::TimeStamp::New();
      h->GetTimeStamp(ts);
      r.t = ts->GetTimeStamp();
      if (r.type == "POLYDATA") {
        if (!unpack_polydata(bytes_.data() + at, body, r)) ++bad_crc;
      }
      if (r.type == "SENSOR") {
        igtl::SensorMessage::Pointer s = igtl::SensorMessage::New();
        s->SetMessageHeader(h);
        s->AllocatePack();
        std::memcpy(s->GetPackBodyPointer(), bytes_.data() + at + IGTL_HEADER_SIZE, body);
        if (s->Unpack(1) & igtl::MessageHeader::UNPACK_BODY) {
          r.length = s->GetLength();
          for (unsigned i = 0; i < r.values.size() && i < s->GetLength(); ++i) r.values[i] = s->GetValue(i);
        } else {
          ++bad_crc;
        }
      }
      replies.push_back(r);
      at += IGTL_HEADER_SIZE + body;
    }
    bytes_.erase(bytes_.begin(), bytes_.begin() + static_cast<std::ptrdiff_t>(at));
  }

  int fd_ = -1;
  int receive_buffer_ = 0;
  std::vector<uint8_t> bytes_;
};

}  // namespace organsim::test
