#pragma once
// Disjoint slices of a sweep's cases: shard i of N takes cases i, i + N,
// i + 2N, ... (in expansion order), so neighbouring values, which often cost
// alike, are spread over the shards. On a Slurm array task the slice comes
// from the environment.
#include <cstddef>
#include <functional>
#include <optional>
#include <string>

namespace organsim {

struct Shard {
  int index = 0;  // 0 .. count-1
  int count = 1;

  bool takes(size_t case_index) const { return static_cast<int>(case_index % count) == index; }
};

// "i/N" or "slurm". `getenv` reads the environment (injectable for tests);
// "slurm" uses SLURM_ARRAY_TASK_ID with SLURM_ARRAY_TASK_COUNT, or with
// SLURM_ARRAY_TASK_MIN and SLURM_ARRAY_TASK_MAX (index = ID - MIN). Throws
// Error(Usage) naming the option or variable at fault, e.g. an index out of
// range.
Shard parse_shard(const std::string& spec, const std::function<const char*(const char*)>& getenv);

}  // namespace organsim
