#include "axon/fps/protocol/firmware_image.hpp"

#include "axon/fps/protocol/error.hpp"

#include <gtest/gtest.h>

#include <string_view>
#include <vector>

using namespace axon::fps::protocol;

TEST(FpsFirmwareImage, Crc32IsZlibs) {
  constexpr std::string_view check = "123456789";
  const std::vector<std::uint8_t> b(check.begin(), check.end());
  EXPECT_EQ(firmware_crc32(b), 0xCBF43926u);  // the standard CRC-32 check value
  EXPECT_EQ(firmware_crc32({}), 0u);
}

TEST(FpsFirmwareImage, HeaderAndChunks) {
  std::vector<std::uint8_t> image(19);
  for (std::size_t i = 0; i < image.size(); ++i) image[i] = static_cast<std::uint8_t>(i);
  const auto f = FirmwareImage::make(image).value();
  EXPECT_EQ(f.header().size, 19u);
  EXPECT_EQ(f.header().crc32, firmware_crc32(image));
  ASSERT_EQ(f.chunk_count(), 3u);
  EXPECT_EQ(f.chunk(0).data.to_hex(), "00 01 02 03 04 05 06 07");
  EXPECT_EQ(f.chunk(1).data.to_hex(), "08 09 0A 0B 0C 0D 0E 0F");
  EXPECT_EQ(f.chunk(2).data.to_hex(), "10 11 12");
  // The header goes out as size then CRC, little-endian.
  const auto p = f.header().encode();
  EXPECT_EQ(p[0], 19);
  EXPECT_EQ(FirmwareUpgradeHeader::decode(p).value(), f.header());
  EXPECT_EQ(FirmwareImage::make({}).error(), ProtocolErrc::value_out_of_range);
}
