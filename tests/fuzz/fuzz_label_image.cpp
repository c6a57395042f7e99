// Harness for the labelled-image readers (.nii .nii.gz .nrrd .inr, by the
// row's extension). The libraries behind them (libniftiio, teem, CGAL
// ImageIO) read files by name, so each input is written to a file first;
// the read either gives a consistent image or an Error naming the file.
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "meshing/label_image.h"
#include "tests/fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace organsim;
  // One file per process, named as the error messages expect ("fuzz.nii").
  static const std::filesystem::path dir = [] {
    const auto d = std::filesystem::temp_directory_path() / ("organsim_fuzz_image_" + std::to_string(getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  const std::filesystem::path path = dir / fuzz::kSource;
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  LabelImage image;
  try {
    image = read_label_image(path);
  } catch (const Error& e) {
    // Messages name the path written here; strip the folder to compare.
    const std::string message = e.what();
    fuzz::require(message.rfind(path.string() + ": ", 0) == 0, "error message does not start with the file name: " + message);
    return 0;
  }
  fuzz::require(image.voxel_count() > 0 && image.voxel_count() <= kMaxImageVoxels, "image accepted with a bad voxel count");
  fuzz::require(static_cast<int64_t>(image.labels.size()) == image.voxel_count(), "labels do not match the size");
  for (int32_t l : image.labels) fuzz::require(l >= 0, "image accepted with a negative label");
  fuzz::require(image.axes.allFinite() && image.origin.allFinite() && image.axes.determinant() != 0,
                "image accepted with a degenerate placement");
  return 0;
}
