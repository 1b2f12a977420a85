// count_byte (util/count_byte.h): the loaders' counts of braces and lines, eight bytes at a
// time, against the plain count on texts that exercise every lane and every round.
#include "util/count_byte.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <string>

namespace rayfarm {
namespace {

std::size_t plain_count(std::string_view s, char c) {
  return static_cast<std::size_t>(std::count(s.begin(), s.end(), c));
}

TEST(CountByte, AgreesWithThePlainCountAtEveryLengthAndOffset) {
  // Bytes near the one counted ('{' is 0x7b): its neighbours, the same with the high bit
  // set (0xfb), zero and 0xff, which a carry between lanes would confuse.
  const char alphabet[] = {'{', 'z', '|', '\x7a', '\xfb', '\0', '\xff', '\x80', '\x7f', '\n'};
  std::mt19937 gen(7);
  std::string text(5000, ' ');
  for (char& ch : text) ch = alphabet[gen() % sizeof alphabet];
  for (std::size_t from = 0; from < 9; ++from)
    for (std::size_t length = 0; from + length <= text.size(); length += length < 40 ? 1 : 97) {
      const std::string_view s(text.data() + from, length);
      for (char c : {'{', '\n', '\0', '\xff', '\xfb'})
        ASSERT_EQ(count_byte(s, c), plain_count(s, c))
            << "offset " << from << ", length " << length << ", byte " << int(c);
    }
}

TEST(CountByte, CountsPastTheLaneLimitOfARound) {
  // Every byte a match: each lane reaches 255 in a round of 255 words, and the rounds add.
  for (std::size_t n : {std::size_t{8 * 255}, std::size_t{8 * 255 + 1}, std::size_t{8 * 255 * 3 + 5},
                        std::size_t{1} << 20}) {
    const std::string all(n, '{');
    EXPECT_EQ(count_byte(all, '{'), n);
    EXPECT_EQ(count_byte(all, '}'), 0u);
  }
}

}  // namespace
}  // namespace rayfarm
