// TokenReader and number parsing for the text mesh formats.
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <ostream>

#include "core/mesh/mesh_io_detail.h"

namespace organsim::mesh_io {

bool label_from_value(double value, int32_t& label) {
  if (!(value >= -2147483648.0 && value <= 2147483647.0) || value != std::floor(value)) return false;
  label = static_cast<int32_t>(value);
  return true;
}

void TokenReader::skip_space() {
  while (pos_ < text_.size()) {
    const char c = text_[pos_];
    if (c == '\n') {
      ++line_;
      ++pos_;
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      ++pos_;
    } else if (comment_ != 0 && c == comment_) {
      while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
    } else {
      break;
    }
  }
}

bool TokenReader::at_end() {
  skip_space();
  return pos_ >= text_.size();
}

std::string_view TokenReader::peek() {
  // Leaves the position alone: binary data may follow the current line.
  const size_t pos = pos_;
  const int line = line_;
  skip_space();
  size_t end = pos_;
  while (end < text_.size() && !std::isspace(static_cast<unsigned char>(text_[end]))) ++end;
  const std::string_view token = text_.substr(pos_, end - pos_);
  pos_ = pos;
  line_ = line;
  return token;
}

std::string_view TokenReader::next(const char* what) {
  skip_space();
  const std::string_view token = peek();
  if (token.empty()) fail(std::string("expected ") + what + ", got the end of the file");
  pos_ += token.size();
  return token;
}

double TokenReader::next_double(const char* what) {
  const std::string_view token = next(what);
  double value = 0;
  if (!parse_double(token, value)) fail(std::string("expected ") + what + " (a number), got '" + std::string(token) + "'");
  return value;
}

int64_t TokenReader::next_int(const char* what) {
  const std::string_view token = next(what);
  int64_t value = 0;
  if (!parse_int(token, value)) fail(std::string("expected ") + what + " (an integer), got '" + std::string(token) + "'");
  return value;
}

int64_t TokenReader::checked_count(int64_t n, int min_bytes, const char* what) {
  if (n < 0) fail(std::string("negative ") + what + " " + std::to_string(n));
  if (n > static_cast<int64_t>((text_.size() - pos_) / static_cast<size_t>(min_bytes))) {
    fail(std::to_string(n) + " " + what + " cannot fit in the rest of the file (truncated or corrupt)");
  }
  return n;
}

void TokenReader::skip_line() { rest_of_line(); }

std::string_view TokenReader::rest_of_line() {
  const size_t start = pos_;
  while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
  std::string_view line = text_.substr(start, pos_ - start);
  if (pos_ < text_.size()) {
    ++pos_;
    ++line_;
  }
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  return line;
}

void TokenReader::fail(const std::string& message) const {
  throw input_error(file_, "line " + std::to_string(line_) + ": " + message);
}

bool parse_double(std::string_view token, double& value) {
  if (token.empty()) return false;
  if (token.front() == '+') token.remove_prefix(1);
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  return ec == std::errc() && end == token.data() + token.size();
}

bool parse_int(std::string_view token, int64_t& value) {
  if (token.empty()) return false;
  if (token.front() == '+') token.remove_prefix(1);
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  return ec == std::errc() && end == token.data() + token.size();
}

void write_point(std::ostream& out, const Vec3& p) {
  char buffer[3 * 32];
  char* end = buffer;
  for (int c = 0; c < 3; ++c) {
    if (c > 0) *end++ = ' ';
    end = std::to_chars(end, buffer + sizeof buffer, p[c]).ptr;
  }
  out.write(buffer, end - buffer);
}

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

void check_surface_indices(const TriangleMesh& mesh, const std::string& source) {
  const auto n = static_cast<int64_t>(mesh.points.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    for (int32_t v : mesh.faces[f]) {
      if (v < 0 || v >= n) {
        throw input_error(source, "face " + std::to_string(f) + " refers to vertex " + std::to_string(v) +
                                      ", expected an index in [0, " + std::to_string(n) + ")");
      }
    }
  }
  for (size_t i = 0; i < mesh.points.size(); ++i) {
    if (!mesh.points[i].allFinite()) {
      throw input_error(source, "vertex " + std::to_string(i) + " has a non-finite coordinate");
    }
  }
}

}  // namespace organsim::mesh_io
