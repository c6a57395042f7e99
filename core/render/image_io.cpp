#include "core/render/image_io.h"

#include <opencv2/imgcodecs.hpp>

#include "core/util/atomic_file.h"
#include "core/util/error.h"

namespace organsim {

void write_image_atomically(const std::filesystem::path& path, const cv::Mat& bgr) {
  write_path_atomically(path, [&](const std::filesystem::path& tmp) {
    bool ok = false;
    try {
      ok = cv::imwrite(tmp.string(), bgr);
    } catch (const cv::Exception& e) {
      throw Error(ErrorKind::Output, path.string() + ": OpenCV cannot write the image: " + e.what());
    }
    if (!ok) throw Error(ErrorKind::Output, path.string() + ": OpenCV cannot write the image");
  });
}

}  // namespace organsim
