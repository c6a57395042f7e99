#pragma once
// Reading and writing meshes without CGAL. Format by file extension.
// Every error names the file and, where there is one, the line or element.
#include <filesystem>
#include <string_view>

#include "core/mesh/tet_mesh.h"

namespace organsim {

// Closed triangle surfaces: .off, .obj, .stl (ASCII and binary), .ply (ASCII
// and binary little/big endian). Throws Error(Input).
TriangleMesh read_surface(const std::filesystem::path& path);
void write_surface(const std::filesystem::path& path, const TriangleMesh& mesh);  // .off .obj .stl .ply

// Tetrahedral meshes: medit .mesh, VTK legacy .vtk (unstructured grid, tets),
// Gmsh .msh (2.2 ASCII; 4.1 ASCII where supported). Throws Error(Input).
TetMesh read_tet_mesh(const std::filesystem::path& path);
// Writes .mesh or .vtk by extension, atomically (temporary name + rename).
void write_tet_mesh(const std::filesystem::path& path, const TetMesh& mesh);

// The same from bytes already in memory: `source` names the file in messages
// and its extension picks the format (the fuzz harnesses in tests/fuzz enter
// here, so they see exactly what a file on disk would).
TriangleMesh parse_surface(std::string_view bytes, const std::string& source);
TetMesh parse_tet_mesh(std::string_view bytes, const std::string& source);

bool is_surface_path(const std::filesystem::path& path);   // by extension
bool is_tet_mesh_path(const std::filesystem::path& path);  // by extension

}  // namespace organsim
