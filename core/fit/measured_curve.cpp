#include "core/fit/measured_curve.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/util/atomic_file.h"
#include "core/util/error.h"

namespace organsim {

namespace {

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream in(line);
  std::string cell;
  while (std::getline(in, cell, ',')) {
    const auto b = cell.find_first_not_of(" \t\r"), e = cell.find_last_not_of(" \t\r");
    cells.push_back(b == std::string::npos ? "" : cell.substr(b, e - b + 1));
  }
  return cells;
}

double column_value(const ForceSamples& s, size_t i, const std::string& column) {
  if (column == "force") return s.force[i].norm();
  return s.force[i][column == "fx" ? 0 : column == "fy" ? 1 : 2];
}

}  // namespace

MeasuredCurve read_measured_curve(const std::filesystem::path& path) {
  return parse_measured_curve(read_text_file(path), path.string());
}

MeasuredCurve parse_measured_curve(std::string_view text, const std::string& source) {
  std::istringstream in{std::string(text)};
  MeasuredCurve c;
  std::string line;
  int line_no = 0;
  bool header = false;
  while (std::getline(in, line)) {
    ++line_no;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const std::vector<std::string> cells = split(line);
    const std::string where = "line " + std::to_string(line_no) + ": ";
    if (!header) {
      header = true;
      if (cells.size() < 2 || (cells[0] != "t" && cells[0] != "displacement"))
        throw input_error(source, where +
                                      "expected a header 't' or 'displacement' followed by force columns "
                                      "(force, fx, fy, fz)");
      c.abscissa = cells[0] == "t" ? MeasuredCurve::Abscissa::Time : MeasuredCurve::Abscissa::Displacement;
      for (size_t k = 1; k < cells.size(); ++k) {
        const std::string& name = cells[k];
        if (name != "force" && name != "fx" && name != "fy" && name != "fz")
          throw input_error(
              source, where + "column " + std::to_string(k + 1) + " '" + name + "': expected force, fx, fy or fz");
        if (std::count(c.columns.begin(), c.columns.end(), name))
          throw input_error(source, where + "column '" + name + "' appears twice");
        c.columns.push_back(name);
      }
      c.force.resize(c.columns.size());
      continue;
    }
    if (cells.size() != c.columns.size() + 1)
      throw input_error(source, where + "expected " + std::to_string(c.columns.size() + 1) + " values, got " +
                                    std::to_string(cells.size()));
    std::vector<double> values;
    for (size_t k = 0; k < cells.size(); ++k) {
      size_t used = 0;
      double v = NAN;
      try {
        v = std::stod(cells[k], &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != cells[k].size() || cells[k].empty() || !std::isfinite(v))
        throw input_error(source,
                          where + "column " + std::to_string(k + 1) + ": expected a number, got '" + cells[k] + "'");
      values.push_back(v);
    }
    if (!c.x.empty() && !(values[0] > c.x.back()))
      throw input_error(source, where + "the first column must increase strictly");
    c.x.push_back(values[0]);
    for (size_t k = 1; k < values.size(); ++k) c.force[k - 1].push_back(values[k]);
  }
  if (!header) throw input_error(source, "empty: expected a header line and samples");
  if (c.x.size() < 2) throw input_error(source, "expected at least 2 samples");
  return c;
}

std::vector<std::vector<double>> simulated_columns(const MeasuredCurve& curve, const ForceSamples& samples,
                                                   const Vec3& tool_start) {
  std::vector<double> x(samples.size());
  for (size_t i = 0; i < samples.size(); ++i)
    x[i] = curve.abscissa == MeasuredCurve::Abscissa::Time ? samples.t[i]
                                                           : (samples.tool_position[i] - tool_start).norm();
  std::vector<std::vector<double>> out(curve.columns.size());
  for (size_t k = 0; k < curve.columns.size(); ++k) {
    for (double at : curve.x) {
      // Samples need not be monotonic in displacement (a tool that returns):
      // the first bracketing pair in order is used.
      double v = samples.size() ? column_value(samples, at <= x.front() ? 0 : samples.size() - 1, curve.columns[k]) : NAN;
      for (size_t i = 1; i < x.size(); ++i) {
        const double a = x[i - 1], b = x[i];
        if ((at - a) * (at - b) <= 0 && a != b) {
          const double s = (at - a) / (b - a);
          v = (1 - s) * column_value(samples, i - 1, curve.columns[k]) + s * column_value(samples, i, curve.columns[k]);
          break;
        }
      }
      out[k].push_back(v);
    }
  }
  return out;
}

}  // namespace organsim
