#include "meshing/gzip_stream.h"

#include <zlib.h>

#include <fstream>
#include <vector>

#include "core/util/error.h"

namespace organsim::image_io {

bool is_gzip_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  char magic[2] = {};
  return in.read(magic, 2) && static_cast<unsigned char>(magic[0]) == 0x1f && static_cast<unsigned char>(magic[1]) == 0x8b;
}

int64_t gzip_content_bytes(const std::filesystem::path& path, const std::string& source, int64_t offset) {
  std::ifstream in(path, std::ios::binary);
  if (!in || !in.seekg(offset)) throw input_error(source, "cannot open it");
  z_stream z{};
  // 16 + MAX_WBITS: gzip framing only (header, trailer with CRC-32 and length).
  if (inflateInit2(&z, 16 + MAX_WBITS) != Z_OK) throw input_error(source, "zlib could not start inflating");
  struct End {
    z_stream* z;
    ~End() { inflateEnd(z); }
  } end{&z};
  std::vector<unsigned char> input(1 << 16), output(1 << 18);
  int64_t content = 0, consumed = offset;
  bool member_ended = false;  // the last member's trailer was read and checked
  while (true) {
    if (z.avail_in == 0) {
      in.read(reinterpret_cast<char*>(input.data()), static_cast<std::streamsize>(input.size()));
      z.next_in = input.data();
      z.avail_in = static_cast<uInt>(in.gcount());
      if (z.avail_in == 0) break;
    }
    if (member_ended) {
      // Another member may follow (gzip files may be concatenated); nothing else may.
      if (z.next_in[0] != 0x1f) {
        throw input_error(source, "bytes follow the gzip stream's end at byte " + std::to_string(consumed) +
                                      " (not another gzip member)");
      }
      inflateReset(&z);
      member_ended = false;
    }
    const uInt before = z.avail_in;
    z.next_out = output.data();
    z.avail_out = static_cast<uInt>(output.size());
    const int status = inflate(&z, Z_NO_FLUSH);
    content += static_cast<int64_t>(output.size() - z.avail_out);
    consumed += before - z.avail_in;
    if (status == Z_STREAM_END) {
      member_ended = true;
    } else if (status != Z_OK && status != Z_BUF_ERROR) {
      throw input_error(source, std::string("damaged gzip stream at byte ") + std::to_string(consumed) + ": " +
                                    (z.msg != nullptr ? z.msg : "zlib error " + std::to_string(status)));
    }
  }
  if (!member_ended) {
    throw input_error(source, "the gzip stream is cut short: it ends after " + std::to_string(consumed) +
                                  " bytes without its end and checksum (" + std::to_string(content) +
                                  " bytes inflated); an interrupted download or copy?");
  }
  return content;
}

void require_whole_gzip(const std::filesystem::path& path, const std::string& source, int64_t offset, int64_t needed,
                        const std::string& what) {
  const int64_t content = gzip_content_bytes(path, source, offset);
  if (content < needed) {
    throw input_error(source, "the gzip stream inflates to " + std::to_string(content) + " bytes; the header asks for " +
                                  std::to_string(needed) + " (" + what + ")");
  }
}

}  // namespace organsim::image_io
