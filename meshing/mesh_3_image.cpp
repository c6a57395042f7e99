// CGAL Mesh_3 on a labelled image (the only TU that instantiates Mesh_3 with
// Labeled_mesh_domain_3): one conforming mesh, each tet in one label's
// subdomain, interfaces between labels shared.
#include "meshing/mesh_3_image.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Image_3.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_3/initialize_triangulation_from_labeled_image.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_constant_domain_field_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Random.h>
#include <CGAL/make_mesh_3.h>
#include <CGAL/refine_mesh_3.h>

#include <cstring>
#include <iostream>
#include <set>
#include <sstream>

#include "meshing/complex_to_tet_mesh.h"

namespace organsim {

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Domain = CGAL::Labeled_mesh_domain_3<Kernel>;
// Sequential: the parallel mesher is not deterministic.
using Triangulation = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using Complex = CGAL::Mesh_complex_3_in_triangulation_3<Triangulation>;
using Criteria = CGAL::Mesh_criteria_3<Triangulation>;
using SizingField = CGAL::Mesh_constant_domain_field_3<Domain::R, Domain::Index>;
constexpr unsigned kSeed = 0;

// CGAL's image initialisation reports its progress on std::cout, which
// carries `organsim mesh --json`'s output: silence it while it runs.
class SilenceStdout {
 public:
  SilenceStdout() : previous_(std::cout.rdbuf(sink_.rdbuf())) {}
  ~SilenceStdout() { std::cout.rdbuf(previous_); }
  SilenceStdout(const SilenceStdout&) = delete;
  SilenceStdout& operator=(const SilenceStdout&) = delete;

 private:
  std::ostringstream sink_;
  std::streambuf* previous_;
};
}  // namespace

struct Mesh3ImageDomain::Impl {
  CGAL::Image_3 image;
  CGAL::Random random{kSeed};
  std::unique_ptr<Domain> domain;
  std::set<int32_t> labels;  // present in the grid, 0 excluded
};

Mesh3ImageDomain::Mesh3ImageDomain(const LabelGrid& grid) : impl_(std::make_unique<Impl>()) {
  const auto [nx, ny, nz] = grid.size;
  const auto px = static_cast<size_t>(nx + 2), py = static_cast<size_t>(ny + 2), pz = static_cast<size_t>(nz + 2);
  _image* im = _createImage(px, py, pz, 1, grid.spacing.x(), grid.spacing.y(), grid.spacing.z(), sizeof(int32_t),
                            WK_FIXED, SGN_SIGNED);
  // The padding voxel 0 lies one spacing before the grid's voxel 0.
  im->tx = static_cast<float>(-grid.spacing.x());
  im->ty = static_cast<float>(-grid.spacing.y());
  im->tz = static_cast<float>(-grid.spacing.z());
  auto* data = static_cast<int32_t*>(im->data);
  std::memset(data, 0, px * py * pz * sizeof(int32_t));
  const std::vector<int32_t>& labels = *grid.labels;
  for (int64_t k = 0; k < nz; ++k) {
    for (int64_t j = 0; j < ny; ++j) {
      for (int64_t i = 0; i < nx; ++i) {
        const int32_t l = labels[static_cast<size_t>(i + nx * (j + ny * k))];
        data[static_cast<size_t>(i + 1) + px * (static_cast<size_t>(j + 1) + py * static_cast<size_t>(k + 1))] = l;
        if (l != 0) impl_->labels.insert(l);
      }
    }
  }
  impl_->image = CGAL::Image_3(im);
  // The error bound is relative to the bounding box, in grid units (a voxel
  // is about 1): far below a voxel.
  impl_->domain = std::make_unique<Domain>(Domain::create_labeled_image_mesh_domain(
      impl_->image, CGAL::parameters::relative_error_bound = 1e-6, CGAL::parameters::p_rng = &impl_->random));
}

Mesh3ImageDomain::~Mesh3ImageDomain() = default;

TetMesh Mesh3ImageDomain::mesh(const Mesh3ImageCriteria& c) const {
  using namespace CGAL::parameters;
  impl_->random = CGAL::Random(kSeed);
  CGAL::get_default_random() = CGAL::Random(kSeed);
  const Domain& domain = *impl_->domain;
  const auto size_of = [&](int32_t label) {
    const auto it = c.label_cell_size.find(label);
    return it == c.label_cell_size.end() ? c.cell_size : it->second;
  };
  // Cells: each label's size; facets on the interface between two labels
  // (or a label and the outside): the smaller of the two.
  SizingField cell_field(c.cell_size), facet_field(c.cell_size);
  for (int32_t a : impl_->labels) {
    cell_field.set_size(size_of(a), 3, domain.index_from_subdomain_index(a));
    for (int32_t b : impl_->labels) {
      if (b <= a) continue;
      const double h = std::min(size_of(a), size_of(b));
      facet_field.set_size(h, 2, domain.index_from_surface_patch_index(Domain::Surface_patch_index(a, b)));
      facet_field.set_size(h, 2, domain.index_from_surface_patch_index(Domain::Surface_patch_index(b, a)));
    }
    facet_field.set_size(size_of(a), 2, domain.index_from_surface_patch_index(Domain::Surface_patch_index(0, a)));
    facet_field.set_size(size_of(a), 2, domain.index_from_surface_patch_index(Domain::Surface_patch_index(a, 0)));
  }
  const Criteria criteria(facet_angle = 25, facet_size = facet_field, facet_distance = c.facet_distance,
                          cell_radius_edge_ratio = 3, cell_size = cell_field);
  // Seeds in every connected component of every label (CGAL's default
  // seeding shoots random rays and can miss a small inclusion).
  Complex complex;
  {
    const SilenceStdout quiet;
    initialize_triangulation_from_labeled_image(complex, domain, impl_->image, criteria, int32_t(0));
  }
  // time_limit = 0: perturbation and exudation run to completion, so the same
  // input gives the same mesh (see mesh_3.cpp).
  if (c.exude) {
    CGAL::refine_mesh_3(complex, domain, criteria, perturb(time_limit = 0, sliver_bound = 10), exude(time_limit = 0));
  } else {
    CGAL::refine_mesh_3(complex, domain, criteria, no_perturb(), no_exude());
  }

  return complex_to_tet_mesh(complex, /*labels=*/true);
}

}  // namespace organsim
