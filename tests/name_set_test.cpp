// NameSet (util/name_set.h): the duplicate checks of the loaders over tens of thousands of
// names, through every growth of its table.
#include "util/name_set.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace rayfarm {
namespace {

TEST(NameSet, FindsEveryNameWithItsFirstPayloadThroughEveryGrowth) {
  std::vector<std::string> names;
  for (int i = 0; i < 20000; ++i) names.push_back("s" + std::to_string(i));
  NameSet<int> set;  // from 16 slots, grown eleven times
  for (int i = 0; i < 20000; ++i) EXPECT_EQ(set.insert(names[i], i), nullptr) << names[i];
  for (int i = 0; i < 20000; ++i) {
    const int* first = set.insert(names[i], -1);  // a repeat: the first payload, unchanged
    ASSERT_NE(first, nullptr) << names[i];
    EXPECT_EQ(*first, i);
    ASSERT_NE(set.find(names[i]), nullptr);
    EXPECT_EQ(*set.find(names[i]), i);
  }
  for (const char* absent : {"s20000", "s-1", "S0", "s0 ", "", "s01"})
    EXPECT_EQ(set.find(absent), nullptr) << absent;
}

TEST(NameSet, NamesDifferingOnlyInLengthOrAfterANulAreDistinct) {
  const std::string text("ab\0ab\0c", 7);
  const std::string_view a(text.data(), 1), ab(text.data(), 2), ab0(text.data(), 3),
      ab0ab(text.data(), 5), ab_again(text.data() + 3, 2);
  NameSet<NoPayload> set;
  set.reserve(4);
  for (std::string_view v : {a, ab, ab0, ab0ab}) EXPECT_EQ(set.insert(v, {}), nullptr);
  EXPECT_NE(set.insert(ab_again, {}), nullptr) << "the same text elsewhere is the same name";
  EXPECT_EQ(set.find(std::string_view(text.data() + 1, 1)), nullptr);  // "b"
}

TEST(NameSet, AnEmptyNameIsANameLikeAnyOther) {
  NameSet<int> set;
  EXPECT_EQ(set.find(std::string_view()), nullptr);
  EXPECT_EQ(set.insert(std::string_view(), 7), nullptr);  // a view with no text at all
  ASSERT_NE(set.find(""), nullptr);
  EXPECT_EQ(*set.find(""), 7);
  EXPECT_NE(set.insert("", 8), nullptr);
  EXPECT_EQ(set.find("x"), nullptr);
}

}  // namespace
}  // namespace rayfarm
