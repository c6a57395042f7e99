#pragma once
// Reading and writing meshes without CGAL. Format by file extension.
// Every error names the file and, where there is one, the line or element.
#include <filesystem>

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

bool is_surface_path(const std::filesystem::path& path);   // by extension
bool is_tet_mesh_path(const std::filesystem::path& path);  // by extension

}  // namespace organsim
