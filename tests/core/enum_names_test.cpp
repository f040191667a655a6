// The generic enum <-> name table (core/enum_names.hpp).

#include "hapticlab/core/enum_names.hpp"

#include <gtest/gtest.h>

namespace hapticlab::enum_names_test {
namespace {

enum class Fruit { kApple, kPear, kQuince };
constexpr EnumTable<Fruit, 2> kPartial{{{Fruit::kApple, "apple"}, {Fruit::kPear, "pear"}}};

TEST(EnumNames, NamesAndValuesRoundTrip) {
  static_assert(NameOf(kPartial, Fruit::kPear) == "pear");  // usable at compile time
  EXPECT_EQ(NameOf(kPartial, Fruit::kApple), "apple");
  EXPECT_EQ(FromName(kPartial, "pear"), Fruit::kPear);
  EXPECT_EQ(FromName(kPartial, "Pear"), std::nullopt) << "names match exactly";
  EXPECT_EQ(Names(kPartial), (std::vector<std::string>{"apple", "pear"}));
  // A value its table lacks has no name (each enum's own test checks its table is whole).
  EXPECT_TRUE(NameOf(kPartial, Fruit::kQuince).empty());
}

TEST(EnumNames, ParseNameListsTheNamesInItsError) {
  EXPECT_EQ(ParseName(kPartial, "apple", "f.toml", 3, "fruit"), Fruit::kApple);
  try {
    ParseName(kPartial, "plum", "f.toml", 3, "fruit");
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    ASSERT_EQ(e.diagnostics().size(), 1u);
    const auto& d = e.diagnostics()[0];
    EXPECT_EQ(d.file, "f.toml");
    EXPECT_EQ(d.line, 3);
    EXPECT_EQ(d.field, "fruit");
    EXPECT_EQ(d.message, "expected one of apple, pear, got 'plum'");
  }
}

}  // namespace
}  // namespace hapticlab::enum_names_test
