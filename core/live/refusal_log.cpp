#include "core/live/refusal_log.h"

namespace organsim {

void RefusalLog::refuse(const std::string& kind, const std::string& client, const std::string& what) {
  const int64_t n = ++counts_[kind];
  if (!out_ || n > logged_per_kind_) return;
  *out_ << "organsim serve: refused from " << client << ": " << what;
  if (n == logged_per_kind_) *out_ << " (further refusals of this kind are only counted)";
  *out_ << "\n";
}

int64_t RefusalLog::total() const {
  int64_t n = 0;
  for (const auto& [kind, count] : counts_) n += count;
  return n;
}

nlohmann::json RefusalLog::counts() const {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [kind, count] : counts_) j[kind] = count;
  return j;
}

}  // namespace organsim
