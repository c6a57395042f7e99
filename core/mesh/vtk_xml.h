#pragma once
// VTK XML writers for ParaView and any VTK client: .vtu (tets), .vtp
// (triangles) and the .pvd collection that makes a time series of them.
// Arrays are written as inline base64 binary with UInt64 headers, in the
// host's byte order (declared in the file). Lengths in metres.
#include <iosfwd>
#include <string>
#include <utility>
#include <vector>

#include "core/mesh/tet_mesh.h"

namespace organsim {

// A named point or cell array: `components` values per point (or cell).
struct VtkArray {
  std::string name;
  int components = 1;
  std::vector<double> values;  // (n x components)
  bool as_uint8 = false;       // written as UInt8 (masks), else Float64
  bool as_int32 = false;       // written as Int32 (labels)
};

struct VtkAttributes {
  std::vector<VtkArray> point_data;
  std::vector<VtkArray> cell_data;
};

void write_vtu(std::ostream& out, const std::vector<Vec3>& points, const std::vector<Tet>& tets,
               const VtkAttributes& attributes = {});
void write_vtp(std::ostream& out, const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
               const VtkAttributes& attributes = {});

// The cell array `label` (Int32) of a labelled mesh's tets.
VtkArray label_cell_array(const std::vector<int32_t>& labels);

// A ParaView collection: (time in s, file relative to the .pvd) per step.
void write_pvd(std::ostream& out, const std::vector<std::pair<double, std::string>>& steps);

}  // namespace organsim
