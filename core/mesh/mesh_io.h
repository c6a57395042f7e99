#pragma once
// Reading and writing meshes without CGAL. Format by file extension.
// Every error names the file and, where there is one, the line or element.
#include <filesystem>
#include <string_view>

#include "core/mesh/tet_mesh.h"

namespace organsim {

// Closed triangle surfaces: .off, .obj, .stl (ASCII and binary), .ply (ASCII
// and binary little/big endian), VTK polydata: legacy .vtk (ASCII or binary)
// and XML .vtp (ascii, base64 binary or raw appended). Throws Error(Input).
TriangleMesh read_surface(const std::filesystem::path& path);
// .off .obj .stl .ply .vtk (legacy polydata) .vtp, atomically.
void write_surface(const std::filesystem::path& path, const TriangleMesh& mesh);

// Tetrahedral meshes: medit .mesh, VTK legacy .vtk (unstructured grid, tets),
// VTK XML .vtu (also when named .vtk), Gmsh .msh (1.0, 2.2 and 4.1 ASCII).
// Throws Error(Input).
TetMesh read_tet_mesh(const std::filesystem::path& path);
// Writes .mesh, .vtk (legacy) or .vtu (XML) by extension, atomically
// (temporary name + rename).
void write_tet_mesh(const std::filesystem::path& path, const TetMesh& mesh);

// The same from bytes already in memory: `source` names the file in messages
// and its extension picks the format (the fuzz harnesses in tests/fuzz enter
// here, so they see exactly what a file on disk would).
TriangleMesh parse_surface(std::string_view bytes, const std::string& source);
TetMesh parse_tet_mesh(std::string_view bytes, const std::string& source);


// What an existing file holds, by extension; a .vtk file holds either, so its
// first bytes decide (POLYDATA / PolyData: a surface).
bool is_surface_path(const std::filesystem::path& path);
bool is_tet_mesh_path(const std::filesystem::path& path);
// What may be written, by extension alone.
bool is_surface_output_path(const std::filesystem::path& path);   // .off .obj .stl .ply .vtk .vtp
bool is_tet_mesh_output_path(const std::filesystem::path& path);  // .mesh .vtk .vtu

}  // namespace organsim
