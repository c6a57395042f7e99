#include "igtl/igtl_stream.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "igtl_header.h"
#include "igtl_string.h"
#include "igtl_transform.h"
#include "igtl_util.h"

namespace organsim {

namespace {

constexpr size_t kTransformContent = 12 * sizeof(float);  // R (3x3, column by column), then the translation
// A TRANSFORM or STRING body with protocol 3's extended header and metadata
// is kept whole for its CRC; more than this is no pose and no command.
constexpr uint64_t kMaxKeptBody = 64 * 1024;

uint16_t be16(const uint8_t* p) { return static_cast<uint16_t>((p[0] << 8) | p[1]); }
uint32_t be32(const uint8_t* p) {
  return (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | uint32_t{p[3]};
}

// A header name field: the characters up to the first NUL, all printable;
// nullopt when one is not (the bytes are not a header).
std::optional<std::string> header_name(const char* field, size_t size) {
  const size_t n = static_cast<size_t>(std::find(field, field + size, '\0') - field);
  for (size_t i = 0; i < n; ++i)
    if (field[i] < 0x20 || field[i] > 0x7e) return std::nullopt;
  return std::string(field, n);
}

IgtlMessage refusal(const std::string& type, const std::string& device, const std::string& kind, const std::string& what) {
  IgtlMessage m;
  m.type = type;
  m.device = device;
  m.refused_kind = kind;
  m.refused = what;
  return m;
}

IgtlMessage transform_content(const std::string& type, const std::string& device, const uint8_t* content, uint64_t size) {
  if (size != kTransformContent)
    return refusal(type, device, "malformed_body",
                   "TRANSFORM content of " + std::to_string(size) + " bytes (expected " +
                       std::to_string(kTransformContent) + ")");
  igtl_float32 v[12];
  std::memcpy(v, content, kTransformContent);
  igtl_transform_convert_byte_order(v);
  IgtlMessage m;
  m.type = type;
  m.device = device;
  m.transform = true;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m.matrix[static_cast<size_t>(4 * r + c)] = v[3 * c + r];
    m.matrix[static_cast<size_t>(4 * r + 3)] = v[9 + r];
  }
  m.matrix[12] = m.matrix[13] = m.matrix[14] = 0;
  m.matrix[15] = 1;
  return m;
}

// STRING content: the encoding (a MIBenum, not checked: commands are ASCII
// and the session refuses what it cannot read) and the length, then the bytes.
IgtlMessage string_content(const std::string& type, const std::string& device, const uint8_t* content, uint64_t size) {
  if (size < IGTL_STRING_HEADER_SIZE || size != IGTL_STRING_HEADER_SIZE + uint64_t{be16(content + 2)})
    return refusal(type, device, "malformed_body",
                   "STRING content of " + std::to_string(size) + " bytes (expected 4 + the length it gives)");
  IgtlMessage m;
  m.type = type;
  m.device = device;
  m.text = true;
  m.content.assign(reinterpret_cast<const char*>(content) + IGTL_STRING_HEADER_SIZE, size - IGTL_STRING_HEADER_SIZE);
  return m;
}

}  // namespace

void IgtlStream::append(const uint8_t* data, size_t size) {
  if (broken()) return;
  compact();  // drops what next() consumed, once per append rather than per message
  buffer_.insert(buffer_.end(), data, data + size);
}

void IgtlStream::compact() {
  if (offset_ == 0) return;
  buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(offset_));
  offset_ = 0;
}

bool IgtlStream::read_header() {
  if (buffered() < IGTL_HEADER_SIZE) return false;
  igtl_header h;
  static_assert(sizeof(igtl_header) == IGTL_HEADER_SIZE);
  std::memcpy(&h, buffer_.data() + offset_, IGTL_HEADER_SIZE);
  igtl_header_convert_byte_order(&h);
  const auto type = header_name(h.name, IGTL_HEADER_TYPE_SIZE);
  const auto device = header_name(h.device_name, IGTL_HEADER_NAME_SIZE);
  if (!type || type->empty() || !device) {
    broken_ = "malformed header: the message type and device name must be printable ASCII (the stream lost its framing)";
    return false;
  }
  if (h.body_size > kMaxBody) {
    broken_ = "malformed header: a body of " + std::to_string(h.body_size) + " bytes (more than " +
              std::to_string(kMaxBody) + ") for " + *type;
    return false;
  }
  offset_ += IGTL_HEADER_SIZE;
  Pending p;
  p.version = h.version;
  p.type = *type;
  p.device = *device;
  p.body_size = h.body_size;
  p.crc = h.crc;
  p.keep = (*type == "TRANSFORM" || *type == "STRING") && h.body_size <= kMaxKeptBody;
  pending_ = p;
  return true;
}

IgtlMessage IgtlStream::finish_kept(const Pending& p, const uint8_t* body) {
  if (p.version != 1 && p.version != 2)
    return refusal(p.type, p.device, "unsupported_version",
                   p.type + " with header version " + std::to_string(p.version) + " (expected 1 or 2)");
  // The library's crc64 takes a non-const pointer; it only reads.
  std::vector<uint8_t> copy(body, body + p.body_size);
  if (crc64(copy.data(), p.body_size, 0) != p.crc)
    return refusal(p.type, p.device, "bad_crc", p.type + " whose body does not match the header's CRC-64");
  uint64_t begin = 0, end = p.body_size;
  if (p.version == 2) {
    // Protocol 3: extended header (its own size first), content, metadata header and metadata.
    if (p.body_size < 12)
      return refusal(p.type, p.device, "malformed_body", p.type + " (version 2) shorter than its extended header");
    const uint64_t ext = be16(body), meta_header = be16(body + 2), meta = be32(body + 4);
    if (ext < 12 || ext + meta_header + meta > p.body_size)
      return refusal(p.type, p.device, "malformed_body", p.type + " (version 2) whose extended header does not fit its body");
    begin = ext;
    end = p.body_size - meta_header - meta;
  }
  return p.type == "STRING" ? string_content(p.type, p.device, body + begin, end - begin)
                            : transform_content(p.type, p.device, body + begin, end - begin);
}

std::optional<IgtlMessage> IgtlStream::next() {
  if (broken()) return std::nullopt;
  if (!pending_ && !read_header()) {
    return std::nullopt;
  }
  Pending& p = *pending_;
  std::optional<IgtlMessage> out;
  if (p.keep) {
    if (buffered() < p.body_size) {
      return std::nullopt;
    }
    out = finish_kept(p, buffer_.data() + offset_);
    offset_ += p.body_size;
  } else {
    const uint64_t take = std::min<uint64_t>(buffered(), p.body_size - p.skipped);
    offset_ += take;
    p.skipped += take;
    if (p.skipped < p.body_size) {
      return std::nullopt;
    }
    out = p.type == "TRANSFORM" || p.type == "STRING"
              ? refusal(p.type, p.device, "malformed_body", p.type + " body of " + std::to_string(p.body_size) + " bytes")
              : refusal(p.type, p.device, "unknown_type",
                        "a " + p.type + " message (only TRANSFORM drives the tool and STRING carries commands)");
  }
  pending_.reset();
  return out;
}

}  // namespace organsim
