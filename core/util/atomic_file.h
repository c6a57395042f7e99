#pragma once
// Outputs are written under a temporary name in the target directory and
// renamed when complete, so a failed run never leaves a half-written file
// under the final name (rename is atomic within one filesystem).
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <string>

namespace organsim {

// Calls write(stream) on a temporary file next to `path`, then renames it to
// `path`. On any exception the temporary is removed and the error rethrown.
void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& write);

// For writers that need a file name (OpenCV, ...): calls write(temp_path) and
// renames temp_path to `path` afterwards. The temporary keeps the extension of
// `path` so format-by-extension writers pick the right format.
void write_path_atomically(const std::filesystem::path& path,
                           const std::function<void(const std::filesystem::path&)>& write);

std::string read_text_file(const std::filesystem::path& path);

}  // namespace organsim
