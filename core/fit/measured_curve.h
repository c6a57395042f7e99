#pragma once
// A measured force curve for `organsim fit`: CSV with a header line,
//   t,force             force against time (s, N), or
//   displacement,fz     force against the tool's travel from its start (m, N)
// The first column is the abscissa (`t` or `displacement`); the others are any
// of `force` (|F|), `fx`, `fy`, `fz` (the tool reaction's components), N.
// Lines starting with '#' and blank lines are skipped.
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "core/io/force_log.h"

namespace organsim {

struct MeasuredCurve {
  enum class Abscissa { Time, Displacement } abscissa = Abscissa::Time;
  std::vector<double> x;                // s or m, strictly increasing (nsample)
  std::vector<std::string> columns;     // force column names, as in the header
  std::vector<std::vector<double>> force;  // per column, N (ncolumn x nsample)
};

// Throws Error(Input) naming the file, the line and what was expected.
MeasuredCurve read_measured_curve(const std::filesystem::path& path);
// The same from the file's text; errors name `source`.
MeasuredCurve parse_measured_curve(std::string_view text, const std::string& source);

// The simulated counterpart of a measured curve: each column of `curve`
// taken from `samples` and linearly interpolated at the curve's x (held at
// the ends). Displacement is |tool position - its first position|.
std::vector<std::vector<double>> simulated_columns(const MeasuredCurve& curve, const ForceSamples& samples,
                                                   const Vec3& tool_start);

}  // namespace organsim
