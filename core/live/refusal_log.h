#pragma once
// Refused network input, counted by kind and logged with the client's
// address: the first few of each kind in full, then only counted, so a client
// that sends garbage at 1 kHz cannot flood the terminal or slow the loop.
#include <nlohmann/json.hpp>

#include <cstdint>
#include <map>
#include <ostream>
#include <string>

namespace organsim {

class RefusalLog {
 public:
  explicit RefusalLog(std::ostream* out, int32_t logged_per_kind = 5) : out_(out), logged_per_kind_(logged_per_kind) {}
  // `kind` is a short key for the counters ("bad_crc"); `what` the message.
  void refuse(const std::string& kind, const std::string& client, const std::string& what);
  int64_t total() const;
  nlohmann::json counts() const;  // {"bad_crc": 3, ...}

 private:
  std::ostream* out_;
  int32_t logged_per_kind_;
  std::map<std::string, int64_t> counts_;
};

}  // namespace organsim
