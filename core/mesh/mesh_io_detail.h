#pragma once
// Internals shared by the format readers in core/mesh: a text cursor that
// knows its line number (so every error can name it) and the per-format
// entry points that mesh_io.cpp dispatches to by extension.
#include <cstdint>
#include <iosfwd>
#include <string>
#include <string_view>

#include "core/mesh/tet_mesh.h"
#include "core/util/error.h"

namespace organsim::mesh_io {

// Reads whitespace-separated tokens from a whole file held in memory,
// skipping comments that start with `comment` (0 = none) up to the line end.
class TokenReader {
 public:
  TokenReader(std::string_view text, std::string file, char comment = '#')
      : text_(text), file_(std::move(file)), comment_(comment) {}

  bool at_end();                       // true when only whitespace/comments remain
  std::string_view next(const char* what);  // throws "expected <what>" at the end
  std::string_view peek();             // the next token without consuming it; empty at the end
  double next_double(const char* what);
  int64_t next_int(const char* what);
  // Checks a count read from the file before anything is sized by it: not
  // negative, and `n` items of at least `min_bytes` each fit in what is left.
  int64_t checked_count(int64_t n, int min_bytes, const char* what);
  void skip_line();                    // rest of the current line
  std::string_view rest_of_line();     // the rest of the current line, without the newline
  int line() const { return line_; }
  const std::string& file() const { return file_; }
  size_t position() const { return pos_; }
  void set_position(size_t pos, int line) { pos_ = pos; line_ = line; }
  [[noreturn]] void fail(const std::string& message) const;

 private:
  void skip_space();
  std::string_view text_;
  std::string file_;
  char comment_;
  size_t pos_ = 0;
  int line_ = 1;
};

// Number parsing that accepts exactly the token (no trailing garbage).
bool parse_double(std::string_view token, double& value);
bool parse_int(std::string_view token, int64_t& value);

// A tet label read as a number (VTK arrays hold doubles): true when it is a
// whole number in int32 range.
bool label_from_value(double value, int32_t& label);

// Writes "x y z" with the shortest text that reads back to the same doubles.
void write_point(std::ostream& out, const Vec3& p);

// Lower-case extension including the dot (".off").
std::string lower_extension(const std::string& path);

// Surfaces (source = the file name used in messages).
TriangleMesh read_off(std::string_view text, const std::string& source);
TriangleMesh read_obj(std::string_view text, const std::string& source);
TriangleMesh read_stl(std::string_view bytes, const std::string& source);
TriangleMesh read_ply(std::string_view bytes, const std::string& source);
void write_off(std::ostream& out, const TriangleMesh& mesh);
void write_obj(std::ostream& out, const TriangleMesh& mesh);
void write_stl_binary(std::ostream& out, const TriangleMesh& mesh);
void write_ply_ascii(std::ostream& out, const TriangleMesh& mesh);
TriangleMesh read_vtk_polydata(std::string_view bytes, const std::string& source);  // legacy POLYDATA
TriangleMesh read_vtp(std::string_view bytes, const std::string& source);           // XML PolyData
void write_vtk_polydata(std::ostream& out, const TriangleMesh& mesh);

// Tet meshes, before orientation fix-up and validation.
TetMesh read_medit(std::string_view text, const std::string& source);
TetMesh read_vtk(std::string_view bytes, const std::string& source);
TetMesh read_gmsh(std::string_view text, const std::string& source);
TetMesh read_vtu(std::string_view bytes, const std::string& source);  // XML UnstructuredGrid
void write_medit(std::ostream& out, const TetMesh& mesh);
void write_vtk(std::ostream& out, const TetMesh& mesh);

// A face with the wrong number of corners or an index outside [0, npoint).
void check_surface_indices(const TriangleMesh& mesh, const std::string& source);

}  // namespace organsim::mesh_io
