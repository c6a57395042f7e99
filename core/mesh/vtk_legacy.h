#pragma once
// Internals shared by the VTK legacy readers (unstructured grid in vtk_io.cpp,
// polydata in vtk_polydata_io.cpp): the header, numbers as ASCII tokens or
// big-endian binary, and cell lists in the classic and the 5.1 layout.
// vtk_index serves the XML reader (vtk_xml_read.cpp) too.
#include <string>
#include <string_view>
#include <vector>

#include "core/mesh/mesh_io_detail.h"

namespace organsim::mesh_io {

// Reads numbers either as ASCII tokens or as big-endian binary values.
class VtkValues {
 public:
  VtkValues(TokenReader& in, std::string_view bytes, bool binary) : in_(in), bytes_(bytes), binary_(binary) {}
  // Reads n values of `type`; in binary mode they start after the current line.
  std::vector<double> read(int64_t n, std::string_view type, const char* what);

 private:
  TokenReader& in_;
  std::string_view bytes_;
  bool binary_;
};

// Reads the first three lines and "DATASET <type>"; returns the dataset type
// and sets `binary`. Throws naming the file when it is not VTK legacy.
std::string read_vtk_legacy_header(TokenReader& in, bool& binary);

// The cells of a CELLS/POLYGONS/... section whose keyword and first count
// (`n`) were just read: each cell's point ids, -1 for anything that is not a
// whole non-negative number (so that range checks name the cell).
std::vector<std::vector<int64_t>> read_vtk_cell_list(TokenReader& in, VtkValues& values, const std::string& keyword,
                                                     int64_t n);

// Point coordinates of a POINTS section whose keyword was just read.
std::vector<Vec3> read_vtk_points(TokenReader& in, VtkValues& values);

// Skips a METADATA block (VTK 9 writes one after arrays), which ends at a blank line.
void skip_vtk_metadata(TokenReader& in);

// Skips a FIELD block whose keyword was just read.
void skip_vtk_field(TokenReader& in, VtkValues& values);

// "polygon 3 has 4 points; not a triangle surface (...triangulate it first...)".
std::string not_a_triangle(size_t polygon, size_t points);

// Point ids as integers; anything that is not a representable whole number becomes -1.
int64_t vtk_index(double v);

}  // namespace organsim::mesh_io
