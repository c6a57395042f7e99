#pragma once
// One client's TCP byte stream cut into OpenIGTLink messages (header
// version 1, protocol 1-2, and header version 2, protocol 3, whose body
// carries an extended header and metadata around the content). Only
// TRANSFORM (the tool's pose) and STRING (a command, docs/live.md#commands)
// are decoded (through the library's byte-order and CRC-64 functions);
// every other message is skipped without being stored and reported as
// refused. A header that cannot be a message (type or device
// name not printable, body larger than any message we accept) means the
// stream has lost its framing: the stream is broken and the connection must
// be closed (the client may reconnect). This is the code that reads outside
// bytes; tests/fuzz has a harness for it (kind igtl).
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace organsim {

struct IgtlMessage {
  std::string type;    // "TRANSFORM", ...
  std::string device;  // the header's device name
  bool transform = false;               // a well-formed TRANSFORM: matrix holds it
  std::array<double, 16> matrix{};      // row-major 4x4, as sent (client units)
  bool text = false;                    // a well-formed STRING: content holds it
  std::string content;                  // the STRING's bytes as sent (not checked for any encoding)
  std::string refused_kind;             // empty when accepted; "bad_crc", "unknown_type", ...
  std::string refused;                  // what was wrong, for the log
};

class IgtlStream {
 public:
  // The largest body skipped rather than taken as a lost framing (an IMAGE
  // from Slicer is a few MiB; 2^63 is garbage).
  static constexpr uint64_t kMaxBody = uint64_t{256} << 20;

  void append(const uint8_t* data, size_t size);
  // The next complete message, or nullopt when more bytes are needed or the
  // stream is broken.
  std::optional<IgtlMessage> next();
  bool broken() const { return !broken_.empty(); }
  const std::string& broken_reason() const { return broken_; }
  size_t buffered() const { return buffer_.size() - offset_; }

 private:
  std::vector<uint8_t> buffer_;
  size_t offset_ = 0;
  // The message whose header has been read and whose body is not complete yet.
  struct Pending {
    uint16_t version = 0;
    std::string type, device;
    uint64_t body_size = 0, crc = 0;
    bool keep = false;        // TRANSFORM or STRING of a plausible size: the body is kept and checked
    uint64_t skipped = 0;     // other types: body bytes dropped so far
  };
  std::optional<Pending> pending_;
  std::string broken_;

  bool read_header();
  IgtlMessage finish_kept(const Pending& p, const uint8_t* body);
  void compact();
};

}  // namespace organsim
