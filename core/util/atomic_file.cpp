#include "core/util/atomic_file.h"

#include <fstream>
#include <sstream>
#include <unistd.h>

#include "core/util/error.h"

namespace organsim {

namespace fs = std::filesystem;

namespace {
fs::path temporary_name(const fs::path& path) {
  // Same directory (so rename stays on one filesystem), same extension.
  fs::path tmp = path;
  // Built with append: gcc 12 warns falsely (-Wrestrict) on "." + string.
  std::string name(".");
  name.append(path.stem().string()).append(".tmp").append(std::to_string(::getpid()));
  name.append(path.extension().string());
  tmp.replace_filename(name);
  return tmp;
}
}  // namespace

void write_path_atomically(const fs::path& path, const std::function<void(const fs::path&)>& write) {
  if (path.has_parent_path()) fs::create_directories(path.parent_path());
  const fs::path tmp = temporary_name(path);
  try {
    write(tmp);
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) throw Error(ErrorKind::Output, path.string() + ": cannot rename from " + tmp.string() + ": " + ec.message());
  } catch (...) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw;
  }
}

void write_file_atomically(const fs::path& path, const std::function<void(std::ostream&)>& write) {
  write_path_atomically(path, [&](const fs::path& tmp) {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw Error(ErrorKind::Output, path.string() + ": cannot open for writing");
    write(out);
    out.flush();
    if (!out) throw Error(ErrorKind::Output, path.string() + ": write failed");
  });
}

std::string read_text_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    if (!fs::exists(path)) throw input_error(path.string(), "no such file");
    throw input_error(path.string(), "cannot open for reading");
  }
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace organsim
