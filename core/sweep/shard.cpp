#include "core/sweep/shard.h"

#include <cstdlib>

#include "core/util/error.h"

namespace organsim {

namespace {

std::optional<long> whole_number(const std::string& s) {
  if (s.empty() || s.size() > 9 || s.find_first_not_of("0123456789") != std::string::npos) return std::nullopt;
  return std::strtol(s.c_str(), nullptr, 10);
}

Error shard_error(const std::string& message) { return Error(ErrorKind::Usage, "--shard: " + message); }

long env_number(const std::function<const char*(const char*)>& getenv, const char* name) {
  const char* v = getenv(name);
  if (!v) throw shard_error(std::string(name) + " is not set (--shard slurm runs inside a Slurm array task)");
  const auto n = whole_number(v);
  if (!n) throw shard_error(std::string(name) + "=" + v + ": expected a whole number >= 0");
  return *n;
}

Shard checked(long index, long count, const std::string& what) {
  if (count < 1) throw shard_error(what + ": the shard count must be at least 1");
  if (index >= count)
    throw shard_error(what + ": shard index " + std::to_string(index) + " out of range 0.." +
                      std::to_string(count - 1));
  return {static_cast<int>(index), static_cast<int>(count)};
}

}  // namespace

Shard parse_shard(const std::string& spec, const std::function<const char*(const char*)>& getenv) {
  if (spec == "slurm") {
    const long id = env_number(getenv, "SLURM_ARRAY_TASK_ID");
    if (getenv("SLURM_ARRAY_TASK_COUNT")) {
      // COUNT alone does not say where the array starts; MIN does (0 in our scripts).
      const long min = getenv("SLURM_ARRAY_TASK_MIN") ? env_number(getenv, "SLURM_ARRAY_TASK_MIN") : 0;
      if (id < min) throw shard_error("SLURM_ARRAY_TASK_ID is below SLURM_ARRAY_TASK_MIN");
      return checked(id - min, env_number(getenv, "SLURM_ARRAY_TASK_COUNT"), "SLURM_ARRAY_TASK_ID");
    }
    const long min = env_number(getenv, "SLURM_ARRAY_TASK_MIN"), max = env_number(getenv, "SLURM_ARRAY_TASK_MAX");
    if (id < min || max < min) throw shard_error("SLURM_ARRAY_TASK_ID is outside SLURM_ARRAY_TASK_MIN..MAX");
    return checked(id - min, max - min + 1, "SLURM_ARRAY_TASK_ID");
  }
  const size_t slash = spec.find('/');
  const auto index = slash == std::string::npos ? std::nullopt : whole_number(spec.substr(0, slash));
  const auto count = slash == std::string::npos ? std::nullopt : whole_number(spec.substr(slash + 1));
  if (!index || !count) throw shard_error("expected i/N (e.g. 0/3) or \"slurm\" (got \"" + spec + "\")");
  return checked(*index, *count, spec);
}

}  // namespace organsim
