// Format dispatch by extension, orientation fix-up and validation of tet meshes.
#include "core/mesh/mesh_io.h"

#include <fstream>
#include <sstream>

#include "core/mesh/mesh_io_detail.h"
#include "core/mesh/vtk_xml.h"
#include "core/util/atomic_file.h"
#include "core/util/error.h"

namespace organsim {

namespace {

constexpr const char* kSurfaceExtensions = ".off, .obj, .stl, .ply, .vtk (polydata), .vtp";
constexpr const char* kTetExtensions = ".mesh, .vtk (unstructured grid), .vtu, .msh";

std::string read_bytes(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw input_error(path.string(), "is a directory, expected a mesh file");
  return read_text_file(path);  // binary-safe; names the file when missing or unreadable
}

// A .vtk file may be legacy or XML (some tools name XML files .vtk).
bool is_xml(std::string_view bytes) {
  const size_t first = bytes.find_first_not_of(" \t\r\n");
  return first != std::string_view::npos && bytes[first] == '<';
}

// Whether the .vtk file at `path` holds polydata, from its first kilobyte
// (the legacy DATASET line or the XML VTKFile type). Unreadable: false, and
// the tet reader will say why.
bool vtk_file_holds_polydata(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  char head[1024] = {};
  in.read(head, sizeof head);
  const std::string_view text(head, static_cast<size_t>(in.gcount()));
  return text.find("DATASET POLYDATA") != std::string_view::npos ||
         text.find("type=\"PolyData\"") != std::string_view::npos;
}

bool is_surface_extension(const std::string& ext) {
  return ext == ".off" || ext == ".obj" || ext == ".stl" || ext == ".ply" || ext == ".vtk" || ext == ".vtp";
}

bool is_tet_extension(const std::string& ext) {
  return ext == ".mesh" || ext == ".vtk" || ext == ".vtu" || ext == ".msh";
}

}  // namespace

bool is_surface_output_path(const std::filesystem::path& path) {
  return is_surface_extension(mesh_io::lower_extension(path.string()));
}

bool is_tet_mesh_output_path(const std::filesystem::path& path) {
  const std::string ext = mesh_io::lower_extension(path.string());
  return ext == ".mesh" || ext == ".vtk" || ext == ".vtu";
}

bool is_surface_path(const std::filesystem::path& path) {
  const std::string ext = mesh_io::lower_extension(path.string());
  if (ext == ".vtk") return vtk_file_holds_polydata(path);
  return is_surface_extension(ext);
}

bool is_tet_mesh_path(const std::filesystem::path& path) {
  const std::string ext = mesh_io::lower_extension(path.string());
  if (ext == ".vtk") return !vtk_file_holds_polydata(path);
  return is_tet_extension(ext);
}

TriangleMesh read_surface(const std::filesystem::path& path) {
  const std::string source = path.string();
  const std::string ext = mesh_io::lower_extension(source);
  if (!is_surface_extension(ext)) {
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
  else if (ext == ".vtp" || (ext == ".vtk" && is_xml(bytes))) mesh = mesh_io::read_vtp(bytes, source);
  else if (ext == ".vtk") mesh = mesh_io::read_vtk_polydata(bytes, source);
  else throw input_error(source, "unknown surface extension '" + ext + "', expected one of " + kSurfaceExtensions);
  mesh_io::check_surface_indices(mesh, source);
  return mesh;
}

void write_surface(const std::filesystem::path& path, const TriangleMesh& mesh) {
  const std::string ext = mesh_io::lower_extension(path.string());
  if (!is_surface_output_path(path)) {
    throw Error(ErrorKind::Output, path.string() + ": unknown surface extension '" + ext + "', expected one of " +
                                       kSurfaceExtensions);
  }
  write_file_atomically(path, [&](std::ostream& out) {
    if (ext == ".off") mesh_io::write_off(out, mesh);
    else if (ext == ".obj") mesh_io::write_obj(out, mesh);
    else if (ext == ".stl") mesh_io::write_stl_binary(out, mesh);
    else if (ext == ".ply") mesh_io::write_ply_ascii(out, mesh);
    else if (ext == ".vtk") mesh_io::write_vtk_polydata(out, mesh);
    else write_vtp(out, mesh.points, mesh.faces);
  });
}

TetMesh read_tet_mesh(const std::filesystem::path& path) {
  const std::string source = path.string();
  const std::string ext = mesh_io::lower_extension(source);
  if (!is_tet_extension(ext)) {
    throw input_error(source, "unknown tet mesh extension '" + ext + "', expected one of " + kTetExtensions);
  }
  return parse_tet_mesh(read_bytes(path), source);
}

TetMesh parse_tet_mesh(std::string_view bytes, const std::string& source) {
  const std::string ext = mesh_io::lower_extension(source);
  TetMesh mesh;
  if (ext == ".mesh") mesh = mesh_io::read_medit(bytes, source);
  else if (ext == ".vtu" || (ext == ".vtk" && is_xml(bytes))) mesh = mesh_io::read_vtu(bytes, source);
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
  if (!is_tet_mesh_output_path(path)) {
    throw Error(ErrorKind::Output, path.string() + ": unknown tet mesh output extension '" + ext +
                                       "', expected .mesh (medit), .vtk (VTK legacy) or .vtu (VTK XML)");
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
    else if (ext == ".vtk") mesh_io::write_vtk(out, mesh);
    else {
      VtkAttributes attributes;
      if (!mesh.labels.empty()) attributes.cell_data.push_back(label_cell_array(mesh.labels));
      write_vtu(out, mesh.points, mesh.tets, attributes);
    }
  });
}

}  // namespace organsim
