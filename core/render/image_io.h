#pragma once
// Writing images through OpenCV, atomically (temporary name with the same
// extension, then rename), with errors that name the file.
#include <filesystem>
#include <opencv2/core.hpp>

namespace organsim {

// Format by extension (.png, .jpg, ...). Throws Error(Output) on failure.
void write_image_atomically(const std::filesystem::path& path, const cv::Mat& bgr);

}  // namespace organsim
