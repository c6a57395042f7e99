// Gmsh .msh tet meshes, ASCII versions 1.0 ($NOD/$ELM, no $MeshFormat), 2.2
// and 4.1. Linear tetrahedra
// (element type 4) are kept; other elements are read past. Node tags are
// arbitrary numbers in Gmsh: points are the nodes the tets use, in file order.
// A tet's physical tag (its volume entity's first one in 4.1, from
// $Entities) is its label; a file without physical tags gives no labels.
#include <algorithm>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "core/mesh/mesh_io_detail.h"

namespace organsim::mesh_io {

namespace {

void skip_section(TokenReader& in, const std::string& name, bool v1) {
  const std::string end = (v1 ? "$END" : "$End") + name.substr(1);
  while (!in.at_end()) {
    if (in.next(end.c_str()) == end) return;
  }
  in.fail("section " + name + " has no " + end);
}

void expect(TokenReader& in, const char* word) {
  const std::string_view got = in.next(word);
  if (got != word) in.fail(std::string("expected ") + word + ", got '" + std::string(got) + "'");
}

}  // namespace

TetMesh read_gmsh(std::string_view text, const std::string& source) {
  TokenReader in(text, source, 0);
  // Version 1.0 has no $MeshFormat: it starts with $NOD.
  const bool v1 = in.peek() == "$NOD";
  bool v4 = false;
  if (!v1) {
    expect(in, "$MeshFormat");
    const std::string version(in.next("the format version"));
    const int64_t file_type = in.next_int("the file type");
    in.next_int("the data size");
    if (file_type != 0) in.fail("binary .msh is not supported; save the mesh as ASCII (Gmsh: -save -format msh22 or msh41)");
    v4 = version.rfind("4", 0) == 0;
    if (!v4 && version.rfind("2", 0) != 0) in.fail("MSH version " + version + ": expected 2.2 or 4.1");
    expect(in, "$EndMeshFormat");
  }

  std::vector<Vec3> nodes;
  std::unordered_map<int64_t, int32_t> node_index;  // Gmsh tag -> position in `nodes`
  std::vector<std::array<int64_t, 4>> tet_tags;
  std::vector<int> tet_lines;
  std::vector<int64_t> tet_physical;               // 0: none
  std::unordered_map<int64_t, int64_t> volume_physical;  // 4.1: volume entity tag -> its first physical tag
  int64_t physical = 0;                            // of the element being read
  const auto add_node = [&](int64_t tag, const Vec3& p) {
    if (!node_index.emplace(tag, static_cast<int32_t>(nodes.size())).second) in.fail("node " + std::to_string(tag) + " is defined twice");
    nodes.push_back(p);
  };
  // Nodes per element for the types we may read past (Gmsh's numbering).
  const auto nodes_of_type = [&](int64_t type) -> int {
    static const int counts[] = {0, 2, 3, 4, 4, 8, 6, 5, 3, 6, 9, 10, 27, 18, 14, 1, 8, 20, 15, 13};
    if (type < 1 || type >= static_cast<int64_t>(std::size(counts))) in.fail("unsupported element type " + std::to_string(type));
    return counts[type];
  };
  // One element's node tags; tets (type 4) are kept, other types read past.
  const auto read_element_nodes = [&](int64_t type) {
    const int count = nodes_of_type(type);
    std::array<int64_t, 4> tet{};
    const int line = in.line();
    for (int k = 0; k < count; ++k) {
      const int64_t node = in.next_int("an element node");
      if (type == 4) tet[k] = node;
    }
    if (type == 4) {
      tet_tags.push_back(tet);
      tet_lines.push_back(line);
      tet_physical.push_back(physical);
    }
  };

  while (!in.at_end()) {
    const std::string section(in.next("a section"));
    if (v1 && section == "$NOD") {
      const int64_t n = in.checked_count(in.next_int("the node count"), 8, "nodes");
      for (int64_t i = 0; i < n; ++i) {
        const int64_t tag = in.next_int("a node number");
        const double x = in.next_double("a node x"), y = in.next_double("a node y"), z = in.next_double("a node z");
        add_node(tag, Vec3(x, y, z));
      }
      expect(in, "$ENDNOD");
    } else if (v1 && section == "$ELM") {
      // number type physical-region elementary-region node-count nodes...
      const int64_t n = in.checked_count(in.next_int("the element count"), 10, "elements");
      for (int64_t e = 0; e < n; ++e) {
        in.next_int("an element number");
        const int64_t type = in.next_int("an element type");
        physical = in.next_int("the physical region");
        in.next_int("the elementary region");
        const int64_t count = in.next_int("the element's node count");
        if (count != nodes_of_type(type)) {
          in.fail("element " + std::to_string(e) + " of type " + std::to_string(type) + " has " + std::to_string(count) +
                  " nodes, expected " + std::to_string(nodes_of_type(type)));
        }
        read_element_nodes(type);
      }
      expect(in, "$ENDELM");
    } else if (v1) {
      if (section.empty() || section[0] != '$') in.fail("expected a $SECTION, got '" + section + "'");
      skip_section(in, section, true);
    } else if (section == "$Nodes" && !v4) {
      const int64_t n = in.next_int("the node count");
      for (int64_t i = 0; i < n; ++i) {
        const int64_t tag = in.next_int("a node tag");
        const double x = in.next_double("a node x"), y = in.next_double("a node y"), z = in.next_double("a node z");
        add_node(tag, Vec3(x, y, z));
      }
      expect(in, "$EndNodes");
    } else if (section == "$Nodes") {
      const int64_t blocks = in.next_int("the entity block count");
      in.next_int("the node count");
      in.next_int("the minimum node tag");
      in.next_int("the maximum node tag");
      for (int64_t b = 0; b < blocks; ++b) {
        in.next_int("the entity dimension");
        in.next_int("the entity tag");
        const int64_t parametric = in.next_int("the parametric flag");
        const int64_t n = in.checked_count(in.next_int("the block's node count"), 2, "nodes");
        std::vector<int64_t> tags(static_cast<size_t>(n));
        for (auto& t : tags) t = in.next_int("a node tag");
        for (int64_t i = 0; i < n; ++i) {
          const double x = in.next_double("a node x"), y = in.next_double("a node y"), z = in.next_double("a node z");
          if (parametric != 0) in.skip_line();
          add_node(tags[static_cast<size_t>(i)], Vec3(x, y, z));
        }
      }
      expect(in, "$EndNodes");
    } else if (section == "$Elements" && !v4) {
      const int64_t n = in.next_int("the element count");
      for (int64_t e = 0; e < n; ++e) {
        in.next_int("an element tag");
        const int64_t type = in.next_int("an element type");
        const int64_t ntags = in.next_int("the element's tag count");
        physical = 0;
        for (int64_t t = 0; t < ntags; ++t) {
          const int64_t tag = in.next_int("an element tag");
          if (t == 0) physical = tag;  // 2.2: the physical tag comes first
        }
        read_element_nodes(type);
      }
      expect(in, "$EndElements");
    } else if (section == "$Elements") {
      const int64_t blocks = in.next_int("the entity block count");
      in.next_int("the element count");
      in.next_int("the minimum element tag");
      in.next_int("the maximum element tag");
      for (int64_t b = 0; b < blocks; ++b) {
        const int64_t dimension = in.next_int("the entity dimension");
        const int64_t entity = in.next_int("the entity tag");
        const auto it = volume_physical.find(entity);
        physical = dimension == 3 && it != volume_physical.end() ? it->second : 0;
        const int64_t type = in.next_int("the element type");
        const int64_t n = in.next_int("the block's element count");
        for (int64_t e = 0; e < n; ++e) {
          in.next_int("an element tag");
          read_element_nodes(type);
        }
      }
      expect(in, "$EndElements");
    } else if (section == "$Entities" && v4) {
      // Points, curves, surfaces and volumes, each with its physical tags;
      // only the volumes' are kept.
      int64_t counts[4];
      for (int64_t& n : counts) n = in.checked_count(in.next_int("an entity count"), 4, "entities");
      for (int dim = 0; dim < 4; ++dim) {
        for (int64_t e = 0; e < counts[dim]; ++e) {
          const int64_t tag = in.next_int("an entity tag");
          for (int k = 0; k < (dim == 0 ? 3 : 6); ++k) in.next_double("an entity coordinate");
          const int64_t nphysical = in.checked_count(in.next_int("the physical tag count"), 2, "physical tags");
          for (int64_t k = 0; k < nphysical; ++k) {
            const int64_t p = in.next_int("a physical tag");
            if (dim == 3 && k == 0) volume_physical[tag] = p;
          }
          if (dim > 0) {
            const int64_t nbounding = in.checked_count(in.next_int("the bounding entity count"), 2, "bounding entities");
            for (int64_t k = 0; k < nbounding; ++k) in.next_int("a bounding entity tag");
          }
        }
      }
      expect(in, "$EndEntities");
    } else if (!section.empty() && section[0] == '$') {
      skip_section(in, section, false);  // $PhysicalNames, $NodeData, ...
    } else {
      in.fail("expected a $Section, got '" + section + "'");
    }
  }

  // Keep only the nodes that tets use (Gmsh files also hold geometry points), in file order.
  std::vector<Tet> tets(tet_tags.size());
  std::vector<char> used(nodes.size(), 0);
  for (size_t t = 0; t < tet_tags.size(); ++t) {
    for (int k = 0; k < 4; ++k) {
      const auto it = node_index.find(tet_tags[t][k]);
      if (it == node_index.end()) {
        throw input_error(source, "line " + std::to_string(tet_lines[t]) + ": tetrahedron " + std::to_string(t) +
                                      " refers to node " + std::to_string(tet_tags[t][k]) + ", which is not in $Nodes");
      }
      tets[t][k] = it->second;
      used[static_cast<size_t>(it->second)] = 1;
    }
  }
  TetMesh mesh;
  std::vector<int32_t> new_index(nodes.size(), -1);
  for (size_t i = 0; i < nodes.size(); ++i) {
    if (!used[i]) continue;
    new_index[i] = static_cast<int32_t>(mesh.points.size());
    mesh.points.push_back(nodes[i]);
  }
  for (Tet& tet : tets) {
    for (int32_t& v : tet) v = new_index[static_cast<size_t>(v)];
  }
  mesh.tets = std::move(tets);
  if (std::any_of(tet_physical.begin(), tet_physical.end(), [](int64_t p) { return p != 0; })) {
    for (size_t t = 0; t < tet_physical.size(); ++t) {
      if (tet_physical[t] < INT32_MIN || tet_physical[t] > INT32_MAX) {
        throw input_error(source, "line " + std::to_string(tet_lines[t]) + ": tetrahedron " + std::to_string(t) +
                                      " has physical tag " + std::to_string(tet_physical[t]) + ", beyond a 32-bit label");
      }
      mesh.labels.push_back(static_cast<int32_t>(tet_physical[t]));
    }
  }
  return mesh;
}

}  // namespace organsim::mesh_io
