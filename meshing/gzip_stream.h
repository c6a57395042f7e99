#pragma once
// A gzip file read to its very end. The image libraries inflate only as many
// bytes as the header asks for and stop there, so a .gz cut short in its data
// (zero-filled by libniftiio) or missing only its trailer (whose CRC-32 and
// length would have caught the damage) reads as a valid image. Inflating the
// whole stream first, every member's trailer checked by zlib, refuses both.
#include <cstdint>
#include <filesystem>
#include <string>

namespace organsim::image_io {

// Whether the file at `path` starts with gzip's magic bytes (1f 8b).
bool is_gzip_file(const std::filesystem::path& path);

// The bytes the gzip stream starting `offset` bytes into the file at `path`
// (after a NRRD's text header, say) holds once inflated, all its members.
// Throws Error(Input) naming `source` when the stream ends before its
// trailer (cut short), when zlib finds it damaged (a CRC-32 or length
// mismatch, bad deflate data), or when other bytes follow its last member.
int64_t gzip_content_bytes(const std::filesystem::path& path, const std::string& source, int64_t offset = 0);

// Throws Error(Input) naming `source` unless the gzip stream at `offset` is
// whole (gzip_content_bytes) and holds at least `needed` bytes, which the
// header asks for (`what`: "vox_offset 352 + 24 voxels of 2 bytes").
void require_whole_gzip(const std::filesystem::path& path, const std::string& source, int64_t offset, int64_t needed,
                        const std::string& what);

}  // namespace organsim::image_io
