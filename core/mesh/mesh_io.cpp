// Format dispatch by extension, orientation fix-up and validation of tet meshes.
#include "core/mesh/mesh_io.h"

#include <fstream>
#include <sstream>

#include "core/mesh/mesh_io_detail.h"
#include "core/util/atomic_file.h"
#include "core/util/error.h"

namespace organsim {

namespace {

constexpr const char* kSurfaceExtensions = ".off, .obj, .stl, .ply";
constexpr const char* kTetExtensions = ".mesh, .vtk, .msh";

std::string read_bytes(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw input_error(path.string(), "is a directory, expected a mesh file");
  return read_text_file(path);  // binary-safe; names the file when missing or unreadable
}

}  // namespace

bool is_surface_path(const std::filesystem::path& path) {
  const std::string ext = mesh_io::lower_extension(path.string());
  return ext == ".off" || ext == ".obj" || ext == ".stl" || ext == ".ply";
}

bool is_tet_mesh_path(const std::filesystem::path& path) {
  const std::string ext = mesh_io::lower_extension(path.string());
  return ext == ".mesh" || ext == ".vtk" || ext == ".msh";
}

TriangleMesh read_surface(const std::filesystem::path& path) {
  const std::string source = path.string();
  const std::string ext = mesh_io::lower_extension(source);
  if (!is_surface_path(path)) {
    throw input_error(source, "unknown surface extension '" + ext + "', expected one of " + kSurfaceExtensions);
  }
  return parse_surface(read_bytes(path), source);
}

TriangleMesh parse_surface(std::string_view bytes, const std::string& source) {
  const std::string ext = mesh_io::lower_extension(source);
  TriangleMesh mesh;
  if (ext == ".off") mesh = mesh_io::read_off(bytes, source);
  else if (ext == ".obj") mesh = mesh_io::read_obj(bytes, source);
  else if (ext == ".stl") mesh = mesh_io::read_stl(bytes, source);
  else if (ext == ".ply") mesh = mesh_io::read_ply(bytes, source);
  else throw input_error(source, "unknown surface extension '" + ext + "', expected one of " + kSurfaceExtensions);
  mesh_io::check_surface_indices(mesh, source);
  return mesh;
}

void write_surface(const std::filesystem::path& path, const TriangleMesh& mesh) {
  const std::string ext = mesh_io::lower_extension(path.string());
  if (!is_surface_path(path)) {
    throw Error(ErrorKind::Output, path.string() + ": unknown surface extension '" + ext + "', expected one of " +
                                       kSurfaceExtensions);
  }
  write_file_atomically(path, [&](std::ostream& out) {
    if (ext == ".off") mesh_io::write_off(out, mesh);
    else if (ext == ".obj") mesh_io::write_obj(out, mesh);
    else if (ext == ".stl") mesh_io::write_stl_binary(out, mesh);
    else mesh_io::write_ply_ascii(out, mesh);
  });
}

TetMesh read_tet_mesh(const std::filesystem::path& path) {
  const std::string source = path.string();
  const std::string ext = mesh_io::lower_extension(source);
  if (!is_tet_mesh_path(path)) {
    throw input_error(source, "unknown tet mesh extension '" + ext + "', expected one of " + kTetExtensions);
  }
  return parse_tet_mesh(read_bytes(path), source);
}

TetMesh parse_tet_mesh(std::string_view bytes, const std::string& source) {
  const std::string ext = mesh_io::lower_extension(source);
  TetMesh mesh;
  if (ext == ".mesh") mesh = mesh_io::read_medit(bytes, source);
  else if (ext == ".vtk") mesh = mesh_io::read_vtk(bytes, source);
  else if (ext == ".msh") mesh = mesh_io::read_gmsh(bytes, source);
  else throw input_error(source, "unknown tet mesh extension '" + ext + "', expected one of " + kTetExtensions);
  if (mesh.tets.empty()) throw input_error(source, "no tetrahedra, expected a tetrahedral volume mesh");

  // Some tools write every tet with the opposite orientation: flip them all
  // consistently. Mixed orientations are left to validate_tet_mesh, which
  // names the first inverted tet.
  const auto n = static_cast<int32_t>(mesh.points.size());
  bool all_negative = true;
  for (const Tet& t : mesh.tets) {
    bool in_range = true;
    for (int32_t v : t) in_range = in_range && v >= 0 && v < n;
    if (!in_range || !(signed_volume(mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]], mesh.points[t[3]]) < 0)) {
      all_negative = false;
      break;
    }
  }
  if (all_negative) {
    for (Tet& t : mesh.tets) std::swap(t[2], t[3]);
  }
  validate_tet_mesh(mesh, source);
  return mesh;
}

void write_tet_mesh(const std::filesystem::path& path, const TetMesh& mesh) {
  const std::string ext = mesh_io::lower_extension(path.string());
  if (ext != ".mesh" && ext != ".vtk") {
    throw Error(ErrorKind::Output, path.string() + ": unknown tet mesh output extension '" + ext +
                                       "', expected .mesh (medit) or .vtk (VTK legacy)");
  }
  // A tet mesh we write is one we can read back: every tet positive.
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    const Tet& k = mesh.tets[t];
    if (!(signed_volume(mesh.points[k[0]], mesh.points[k[1]], mesh.points[k[2]], mesh.points[k[3]]) > 0)) {
      throw Error(ErrorKind::Numerical, path.string() + ": not written: tetrahedron " + std::to_string(t) +
                                            " has non-positive volume");
    }
  }
  write_file_atomically(path, [&](std::ostream& out) {
    if (ext == ".mesh") mesh_io::write_medit(out, mesh);
    else mesh_io::write_vtk(out, mesh);
  });
}

}  // namespace organsim
