// IgtlStream: the bytes a client sends, cut into messages. Messages are packed
// by the OpenIGTLink library (an independent writer); broken ones are made
// from its bytes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "igtl/igtl_stream.h"
#include "igtlStatusMessage.h"
#include "igtl_header.h"
#include "igtl_util.h"
#include "tests/live/igtl_test_client.h"

namespace organsim {
namespace igtl_stream_test {
namespace {

using test::IgtlTestClient;

std::vector<IgtlMessage> all(IgtlStream& s) {
  std::vector<IgtlMessage> out;
  while (auto m = s.next()) out.push_back(*m);
  return out;
}

TEST(IgtlStream, ReadsTheLibrarysTransformEvenOneByteAtATime) {
  const std::vector<uint8_t> bytes = IgtlTestClient::transform("Tool", {12.5f, -3.25f, 40.0f});
  IgtlStream s;
  std::vector<IgtlMessage> got;
  for (uint8_t b : bytes) {
    s.append(&b, 1);
    for (auto& m : all(s)) got.push_back(m);
  }
  ASSERT_EQ(got.size(), 1u);
  EXPECT_TRUE(got[0].transform) << got[0].refused;
  EXPECT_EQ(got[0].device, "Tool");
  const std::array<double, 16> expected{1, 0, 0, 12.5, 0, 1, 0, -3.25, 0, 0, 1, 40, 0, 0, 0, 1};
  EXPECT_EQ(got[0].matrix, expected);
  EXPECT_EQ(s.buffered(), 0u);
}

TEST(IgtlStream, ReadsTheRotationRowByRow) {
  igtl::TransformMessage::Pointer m = igtl::TransformMessage::New();
  m->SetDeviceName("Tool");
  igtl::Matrix4x4 r = {{0, -1, 0, 1}, {1, 0, 0, 2}, {0, 0, 1, 3}, {0, 0, 0, 1}};  // 90 degrees about z
  m->SetMatrix(r);
  m->Pack();
  IgtlStream s;
  s.append(static_cast<const uint8_t*>(m->GetPackPointer()), static_cast<size_t>(m->GetPackSize()));
  const auto got = all(s);
  ASSERT_EQ(got.size(), 1u);
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) EXPECT_EQ(got[0].matrix[static_cast<size_t>(4 * i + j)], r[i][j]) << i << "," << j;
}

TEST(IgtlStream, RefusesABadCrcAWrongBodySizeAndOtherTypesAndGoesOn) {
  std::vector<uint8_t> bad_crc = IgtlTestClient::transform("Tool", {1, 2, 3});
  bad_crc.back() ^= 0x01;
  // A TRANSFORM header claiming a 40-byte body (with its right CRC).
  std::vector<uint8_t> short_body = IgtlTestClient::transform("Tool", {1, 2, 3});
  short_body.resize(58 + 40);
  {
    igtl_header h;
    std::memcpy(&h, short_body.data(), 58);
    igtl_header_convert_byte_order(&h);
    h.body_size = 40;
    h.crc = crc64(short_body.data() + 58, 40, 0);
    igtl_header_convert_byte_order(&h);
    std::memcpy(short_body.data(), &h, 58);
  }
  igtl::StatusMessage::Pointer status = igtl::StatusMessage::New();
  status->SetDeviceName("Tool");
  status->SetStatusString("hello");
  status->Pack();
  const auto* sp = static_cast<const uint8_t*>(status->GetPackPointer());
  const std::vector<uint8_t> good = IgtlTestClient::transform("Tool", {4, 5, 6});

  IgtlStream s;
  for (const auto* part : {&bad_crc, &short_body}) s.append(part->data(), part->size());
  s.append(sp, static_cast<size_t>(status->GetPackSize()));
  s.append(good.data(), good.size());
  const auto got = all(s);
  ASSERT_EQ(got.size(), 4u);
  EXPECT_EQ(got[0].refused_kind, "bad_crc");
  EXPECT_EQ(got[1].refused_kind, "malformed_body");
  EXPECT_EQ(got[2].refused_kind, "unknown_type");
  EXPECT_EQ(got[2].type, "STATUS");
  EXPECT_TRUE(got[3].transform);
  EXPECT_EQ(got[3].matrix[3], 4);
  EXPECT_FALSE(s.broken());
}

TEST(IgtlStream, AHeaderThatCannotBeOneBreaksTheStream) {
  IgtlStream garbage;
  const std::vector<uint8_t> ff(58, 0xff);
  garbage.append(ff.data(), ff.size());
  EXPECT_FALSE(garbage.next());
  EXPECT_TRUE(garbage.broken());
  EXPECT_NE(garbage.broken_reason().find("malformed header"), std::string::npos);

  // A printable header whose body size is absurd.
  std::vector<uint8_t> huge = IgtlTestClient::transform("Tool", {1, 2, 3});
  igtl_header h;
  std::memcpy(&h, huge.data(), 58);
  igtl_header_convert_byte_order(&h);
  h.body_size = uint64_t{1} << 62;
  igtl_header_convert_byte_order(&h);
  std::memcpy(huge.data(), &h, 58);
  IgtlStream s;
  s.append(huge.data(), huge.size());
  EXPECT_FALSE(s.next());
  EXPECT_TRUE(s.broken());
}

TEST(IgtlStream, ReadsAVersion2TransformAroundItsExtendedHeaderAndMetadata) {
  // Protocol 3 framing built by hand from the library's version-1 content:
  // a 12-byte extended header, the 48 content bytes, 2 + 8 bytes of metadata header and 5 of metadata.
  const std::vector<uint8_t> v1 = IgtlTestClient::transform("Tool", {7, 8, 9});
  std::vector<uint8_t> body = {0, 12, 0, 10, 0, 0, 0, 5, 0, 0, 0, 1};
  body.insert(body.end(), v1.begin() + 58, v1.end());
  for (int i = 0; i < 15; ++i) body.push_back(static_cast<uint8_t>(i));
  igtl_header h;
  std::memcpy(&h, v1.data(), 58);
  igtl_header_convert_byte_order(&h);
  h.version = 2;
  h.body_size = body.size();
  h.crc = crc64(body.data(), body.size(), 0);
  igtl_header_convert_byte_order(&h);
  std::vector<uint8_t> msg(58);
  std::memcpy(msg.data(), &h, 58);
  msg.insert(msg.end(), body.begin(), body.end());
  IgtlStream s;
  s.append(msg.data(), msg.size());
  const auto got = all(s);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_TRUE(got[0].transform) << got[0].refused;
  EXPECT_EQ(got[0].matrix[3], 7);
  EXPECT_EQ(got[0].matrix[11], 9);
}

TEST(IgtlStream, ReadsTheLibrarysStringAndRefusesABrokenOne) {
  const std::vector<uint8_t> cut = IgtlTestClient::text("Command", "CUT 5 10");
  std::vector<uint8_t> bad_crc = IgtlTestClient::text("Command", "CUT");
  bad_crc.back() ^= 0x01;
  // The length field (body bytes 2-3) one more than the bytes that follow, with the body's right CRC.
  std::vector<uint8_t> long_length = IgtlTestClient::text("Command", "CUT");
  long_length[58 + 3] += 1;
  {
    igtl_header h;
    std::memcpy(&h, long_length.data(), 58);
    igtl_header_convert_byte_order(&h);
    h.crc = crc64(long_length.data() + 58, long_length.size() - 58, 0);
    igtl_header_convert_byte_order(&h);
    std::memcpy(long_length.data(), &h, 58);
  }
  const std::vector<uint8_t> pose = IgtlTestClient::transform("Tool", {4, 5, 6});
  IgtlStream s;
  std::vector<IgtlMessage> got;
  for (const std::vector<uint8_t>* part : std::initializer_list<const std::vector<uint8_t>*>{&cut, &bad_crc, &long_length, &pose}) {
    for (uint8_t b : *part) {
      s.append(&b, 1);
      for (auto& m : all(s)) got.push_back(m);
    }
  }
  ASSERT_EQ(got.size(), 4u);
  EXPECT_TRUE(got[0].text) << got[0].refused;
  EXPECT_EQ(got[0].type, "STRING");
  EXPECT_EQ(got[0].device, "Command");
  EXPECT_EQ(got[0].content, "CUT 5 10");
  EXPECT_EQ(got[1].refused_kind, "bad_crc");
  EXPECT_EQ(got[2].refused_kind, "malformed_body");
  EXPECT_FALSE(got[2].text);
  EXPECT_TRUE(got[3].transform);
  EXPECT_FALSE(s.broken());
}

}  // namespace
}  // namespace igtl_stream_test
}  // namespace organsim
