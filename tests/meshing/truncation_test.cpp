// Every reader a user's file reaches, fed its own valid inputs cut short:
// each accepted seed of the fuzz table (tests/fuzz/harnesses.txt) cut at
// ten points through the file (k * size / 11, k = 1..10) and with its last
// byte dropped, as an interrupted download or copy leaves it. A reader must
// refuse every cut with its clean error, never read the part it got as if it
// were the whole. The same cuts seed the fuzzer (scripts/fuzz.sh).
//
// Exceptions, each with its reason, are listed below: the formats whose
// tail is optional, where a shorter file is itself a valid file; and a cut
// that removes only trailing white space leaves the same document.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <map>

#include "core/util/atomic_file.h"
#include "tests/meshing/fuzz_rows.h"

namespace organsim {
namespace truncation_test {
namespace {

using namespace fuzz_rows;

// Rows whose format has no count or end marker for its tail: a file cut
// after a whole line (or inside a number, which reads as a shorter number)
// is a smaller valid file, so some cuts are accepted. The test requires at
// least one accepted cut of each, so the list cannot outlive its reason.
const std::map<std::string, std::string> kTailIsOptional = {
    {"obj", "OBJ has no element counts and no end marker: its lines stand alone"},
    {"measured_curve", "a CSV curve has no row count: any first rows are a curve"},
    {"vtk", "legacy VTK's attribute sections after the cells are optional (a VTK 5.1 file may end with an empty "
            "CELL_DATA): a file cut between sections is the mesh without its labels"},
};

// The cut points: k * size / 11 for k = 1..10, and size - 1. scripts/fuzz.sh
// makes the same cuts of the same seeds.
std::vector<size_t> cut_points(size_t size) {
  std::vector<size_t> cuts;
  for (size_t k = 1; k <= 10; ++k) cuts.push_back(k * size / 11);
  cuts.push_back(size - 1);
  std::sort(cuts.begin(), cuts.end());
  cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
  return cuts;
}

bool only_space(const std::string& bytes, size_t from) {
  return std::all_of(bytes.begin() + static_cast<std::ptrdiff_t>(from), bytes.end(),
                     [](unsigned char c) { return std::isspace(c) != 0; });
}

bool same_message(const IgtlMessage& a, const IgtlMessage& b) {
  return a.type == b.type && a.device == b.device && a.transform == b.transform && a.matrix == b.matrix &&
         a.text == b.text && a.content == b.content && a.refused_kind == b.refused_kind;
}

// A byte stream has no end to miss: a cut stream gives the messages wholly
// inside the part received, those of the whole stream, in order, and waits
// for the rest of the one it cut (never delivers it in part).
TEST(Truncation, AnIgtlStreamCutShortDeliversOnlyTheMessagesItHoldsWhole) {
  const Row row = [] {
    for (const Row& r : harness_rows()) {
      if (r.kind == "igtl") return r;
    }
    return Row{};
  }();
  ASSERT_EQ(row.kind, "igtl");
  size_t cuts = 0;
  for (const fs::path& seed : row_seeds(row)) {
    SCOPED_TRACE(seed.string());
    const std::string bytes = read_text_file(kRoot / seed);
    const std::vector<IgtlMessage> whole = fuzz::igtl_input(bytes);
    ASSERT_FALSE(whole.empty());
    for (size_t at : cut_points(bytes.size())) {
      const std::vector<IgtlMessage> part = fuzz::igtl_input(std::string_view(bytes).substr(0, at));
      ASSERT_LE(part.size(), whole.size()) << "cut at " << at;
      for (size_t i = 0; i < part.size(); ++i) {
        EXPECT_TRUE(same_message(part[i], whole[i])) << "cut at " << at << ", message " << i;
      }
      if (at == bytes.size() - 1) {
        EXPECT_LT(part.size(), whole.size()) << "the last message was delivered without its last byte";
      }
      ++cuts;
    }
  }
  EXPECT_GT(cuts, 10u);
}

TEST(Truncation, EveryReaderRefusesItsValidInputsCutShort) {
  std::map<std::string, size_t> refused, accepted_as_listed;
  size_t seeds_cut = 0;
  for (const Row& row : harness_rows()) {
    if (row.kind == "igtl") continue;  // a stream: the test above
    const bool tail_optional = kTailIsOptional.count(row.name) > 0;
    const std::string source = "fuzz" + row.ext;
    for (const fs::path& seed : row_seeds(row)) {
      const std::string bytes = read_text_file(kRoot / seed);
      try {
        if (run_harness(row, bytes, source) == 0) continue;
      } catch (const Error&) {
        continue;  // a seed that exists to be refused (FuzzSeeds lists them)
      }
      ++seeds_cut;
      for (size_t at : cut_points(bytes.size())) {
        SCOPED_TRACE(row.name + ": " + seed.string() + " cut to " + std::to_string(at) + " of " +
                     std::to_string(bytes.size()) + " bytes");
        const std::string cut = bytes.substr(0, at);
        // Only trailing white space gone (text, or the newline after a
        // binary block): the same document.
        if (only_space(bytes, at)) continue;
        try {
          run_harness(row, cut, source);
          if (tail_optional) {
            ++accepted_as_listed[row.name];
          } else {
            ADD_FAILURE() << "accepted";
          }
        } catch (const Error& e) {
          // The refusal names the file it refuses.
          EXPECT_NE(std::string(e.what()).find(source), std::string::npos) << e.what();
          ++refused[row.name];
        }
      }
    }
  }
  for (const auto& [name, why] : kTailIsOptional) {
    EXPECT_GT(accepted_as_listed[name], 0u) << name << " is listed as having an optional tail (" << why
                                            << "), but no cut of it was accepted";
  }
  EXPECT_GT(seeds_cut, 40u);
  for (const auto& [name, n] : refused) std::cout << name << ": " << n << " cuts refused\n";
}

}  // namespace
}  // namespace truncation_test
}  // namespace organsim
