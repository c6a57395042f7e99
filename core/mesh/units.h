#pragma once
// Length units of input files. Everything inside organsim is in metres; a
// file in millimetres is scaled by 0.001 as it is read.
#include <optional>
#include <string_view>

#include "core/mesh/tet_mesh.h"

namespace organsim {

// Metres per unit for "mm", "cm" and "m"; nullopt for anything else.
std::optional<double> metres_per_unit(std::string_view unit);

// Multiplies every coordinate by `scale`.
void scale_points(std::vector<Vec3>& points, double scale);

// "0.21 x 0.15 x 0.1 m": the axis-aligned extent of `points`, in metres.
std::string describe_extent(const std::vector<Vec3>& points);

}  // namespace organsim
